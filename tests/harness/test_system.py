"""System setup: chromium for the browser test is found, or installed as root, or the
error says how; ``python -m harness.system`` fails on CI only."""

from __future__ import annotations

import pytest

from harness import system
from renderers import system as apt


def test_chromium_is_found_where_debian_puts_it(monkeypatch, tmp_path):
    browser = tmp_path / "chromium"
    browser.write_bytes(b"")
    monkeypatch.setattr(system, "CHROMIUM_PATH", str(browser))
    monkeypatch.setattr(apt, "_apt_install", lambda package: pytest.fail("no install"))
    assert system.ensure_chromium(install=True) == str(browser)


def test_chromium_is_installed_as_root(monkeypatch, tmp_path):
    """As root, a missing chromium triggers the apt install of Debian's package."""
    browser = tmp_path / "chromium"
    calls = []
    monkeypatch.setattr(system, "CHROMIUM_PATH", str(browser))
    monkeypatch.setattr(apt.os, "geteuid", lambda: 0)
    monkeypatch.setattr(apt.shutil, "which", lambda name: "/usr/bin/apt-get")

    def fake_install(package):
        calls.append(package)
        browser.write_bytes(b"")

    monkeypatch.setattr(apt, "_apt_install", fake_install)
    assert system.ensure_chromium(install=True) == str(browser)
    assert calls == ["chromium"]


def test_missing_chromium_not_root_names_the_command(monkeypatch, tmp_path):
    monkeypatch.setattr(system, "CHROMIUM_PATH", str(tmp_path / "absent"))
    monkeypatch.setattr(apt.os, "geteuid", lambda: 1000)
    with pytest.raises(apt.SystemSetupError) as info:
        system.ensure_chromium(install=True)
    assert "apt-get update && apt-get install -y chromium" in str(info.value)


@pytest.mark.parametrize(("ci", "code"), [("", 0), ("true", 1)])
def test_main_fails_on_missing_chromium_only_on_ci(monkeypatch, tmp_path, capsys, ci, code):
    """Without chromium, setup warns locally (the browser test skips) but fails on CI,
    where the browser test must run."""
    monkeypatch.setattr(system, "configure_drjit", lambda install: "/lib/libLLVM.so.19")
    monkeypatch.setattr(system, "CHROMIUM_PATH", str(tmp_path / "absent"))
    monkeypatch.setattr(apt.os, "geteuid", lambda: 1000)
    monkeypatch.setenv("CI", ci)
    assert system.main() == code
    assert "apt-get install -y chromium" in capsys.readouterr().err


@pytest.mark.parametrize(("cuda", "code"), [(False, 1), (True, 0)])
def test_main_without_libllvm_fails_unless_a_cuda_device_is_present(monkeypatch, capsys,
                                                                    cuda, code):
    """Regression lock: without libLLVM, setup fails, except where a CUDA device is
    present: Mitsuba then traces on cuda_ad_rgb, and the warning says llvm_ad_rgb is
    unavailable."""
    def missing(install):
        raise apt.SystemSetupError("no libLLVM; run: apt-get install -y libllvm19")

    monkeypatch.setattr(system, "configure_drjit", missing)
    monkeypatch.setattr(system, "cuda_device_present", lambda: cuda)
    monkeypatch.setattr(system, "ensure_chromium", lambda install: "/usr/bin/chromium")
    assert system.main() == code
    err = capsys.readouterr().err
    assert "apt-get install -y libllvm19" in err
    assert ("llvm_ad_rgb is unavailable" in err) == cuda
