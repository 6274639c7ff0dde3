"""System setup: Dr.Jit's libLLVM is found, or installed as root, or the error says how."""

from __future__ import annotations

import os

import pytest

from harness import system


def test_found_library_is_configured(monkeypatch):
    """On this machine (tox installs libllvm19 first) the path is set explicitly."""
    monkeypatch.delenv("DRJIT_LIBLLVM_PATH", raising=False)
    path = system.configure_drjit(install=False)
    assert os.path.isfile(path) and "19" in os.path.basename(path)
    assert os.environ["DRJIT_LIBLLVM_PATH"] == path


def test_preset_path_is_honoured(monkeypatch, tmp_path):
    lib = tmp_path / "libLLVM.so.99"
    lib.write_bytes(b"")
    monkeypatch.setenv("DRJIT_LIBLLVM_PATH", str(lib))
    assert system.find_libllvm() == str(lib)


def test_missing_and_not_root_names_the_command(monkeypatch):
    """Without the library and without root, the error gives the exact apt command."""
    monkeypatch.delenv("DRJIT_LIBLLVM_PATH", raising=False)
    monkeypatch.setattr(system, "LLVM_GLOBS", ("/nonexistent/libLLVM.so.19*",))
    monkeypatch.setattr(system.os, "geteuid", lambda: 1000)
    with pytest.raises(system.SystemSetupError) as info:
        system.ensure_libllvm(install=True)
    assert "apt-get update && apt-get install -y libllvm19" in str(info.value)


def test_install_is_attempted_as_root(monkeypatch):
    """As root, a missing library triggers the apt install, then is found."""
    monkeypatch.delenv("DRJIT_LIBLLVM_PATH", raising=False)
    calls = []
    monkeypatch.setattr(system.os, "geteuid", lambda: 0)
    monkeypatch.setattr(system.shutil, "which", lambda name: "/usr/bin/apt-get")

    def fake_install(package):
        calls.append(package)
        monkeypatch.setattr(system, "LLVM_GLOBS", ("/usr/lib/x86_64-linux-gnu/libLLVM.so.19*",))

    monkeypatch.setattr(system, "LLVM_GLOBS", ("/nonexistent/libLLVM.so.19*",))
    monkeypatch.setattr(system, "_apt_install", fake_install)
    assert "19" in system.ensure_libllvm(install=True)
    assert calls == ["libllvm19"]


def test_chromium_is_found_where_debian_puts_it(monkeypatch, tmp_path):
    browser = tmp_path / "chromium"
    browser.write_bytes(b"")
    monkeypatch.setattr(system, "CHROMIUM_PATH", str(browser))
    monkeypatch.setattr(system, "_apt_install", lambda package: pytest.fail("no install"))
    assert system.ensure_chromium(install=True) == str(browser)


def test_chromium_is_installed_as_root(monkeypatch, tmp_path):
    """As root, a missing chromium triggers the apt install of Debian's package."""
    browser = tmp_path / "chromium"
    calls = []
    monkeypatch.setattr(system, "CHROMIUM_PATH", str(browser))
    monkeypatch.setattr(system.os, "geteuid", lambda: 0)
    monkeypatch.setattr(system.shutil, "which", lambda name: "/usr/bin/apt-get")

    def fake_install(package):
        calls.append(package)
        browser.write_bytes(b"")

    monkeypatch.setattr(system, "_apt_install", fake_install)
    assert system.ensure_chromium(install=True) == str(browser)
    assert calls == ["chromium"]


def test_missing_chromium_not_root_names_the_command(monkeypatch, tmp_path):
    monkeypatch.setattr(system, "CHROMIUM_PATH", str(tmp_path / "absent"))
    monkeypatch.setattr(system.os, "geteuid", lambda: 1000)
    with pytest.raises(system.SystemSetupError) as info:
        system.ensure_chromium(install=True)
    assert "apt-get update && apt-get install -y chromium" in str(info.value)


@pytest.mark.parametrize(("ci", "code"), [("", 0), ("true", 1)])
def test_main_fails_on_missing_chromium_only_on_ci(monkeypatch, tmp_path, capsys, ci, code):
    """Without chromium, setup warns locally (the browser test skips) but fails on CI,
    where the browser test must run."""
    monkeypatch.setattr(system, "configure_drjit", lambda install: "/lib/libLLVM.so.19")
    monkeypatch.setattr(system, "CHROMIUM_PATH", str(tmp_path / "absent"))
    monkeypatch.setattr(system.os, "geteuid", lambda: 1000)
    monkeypatch.setenv("CI", ci)
    assert system.main() == code
    assert "apt-get install -y chromium" in capsys.readouterr().err
