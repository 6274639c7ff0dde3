"""The set-up step (``caustics setup``, ``python -m harness.system``): chromium and
libLLVM are found, or installed as root, or the error says how; a missing chromium
fails on CI only. The set-up step is the only code that installs: loading the
Mitsuba runtime without libLLVM raises at first use, naming the command, and runs
nothing."""

from __future__ import annotations

import os
import subprocess

import pytest

from harness import system
from harness.cli import main
from renderers.mitsuba import _mi, llvm
from renderers.system import SystemSetupError


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
    with pytest.raises(SystemSetupError) as info:
        system.ensure_chromium(install=True)
    assert "apt-get update && apt-get install -y chromium" in str(info.value)


def _no_libllvm(monkeypatch) -> None:
    """No libLLVM anywhere: no DRJIT_LIBLLVM_PATH, no file where Debian puts one."""
    monkeypatch.delenv("DRJIT_LIBLLVM_PATH", raising=False)
    monkeypatch.setattr(llvm, "LLVM_GLOBS", ("/nonexistent/libLLVM.so.19*",))


def test_libllvm_is_installed_as_root_and_configured(monkeypatch):
    """As root, the set-up step apt-installs Debian's libllvm19 when none is found,
    finds it and sets DRJIT_LIBLLVM_PATH to it."""
    _no_libllvm(monkeypatch)
    installed = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19*"
    calls = []
    monkeypatch.setattr(system.os, "geteuid", lambda: 0)
    monkeypatch.setattr(system.shutil, "which", lambda name: "/usr/bin/apt-get")
    monkeypatch.setattr(llvm.glob, "glob",
                        lambda pattern: ["/usr/lib/libLLVM.so.19.1"]
                        if pattern == installed and calls else [])

    def fake_install(package):
        calls.append(package)
        monkeypatch.setattr(llvm, "LLVM_GLOBS", (installed,))

    monkeypatch.setattr(system, "_apt_install", fake_install)
    assert system.ensure_libllvm(install=True) == "/usr/lib/libLLVM.so.19.1"
    assert calls == ["libllvm19"]
    assert os.environ["DRJIT_LIBLLVM_PATH"] == "/usr/lib/libLLVM.so.19.1"


def test_missing_libllvm_not_root_names_the_command(monkeypatch):
    """Without the library and without root, the set-up step's error gives the
    exact apt command and installs nothing."""
    _no_libllvm(monkeypatch)
    monkeypatch.setattr(system.os, "geteuid", lambda: 1000)
    monkeypatch.setattr(system, "_apt_install", lambda package: pytest.fail("no install"))
    with pytest.raises(SystemSetupError) as info:
        system.ensure_libllvm(install=True)
    assert "apt-get update && apt-get install -y libllvm19" in str(info.value)


@pytest.mark.parametrize(("ci", "code"), [("", 0), ("true", 1)])
def test_setup_fails_on_missing_chromium_only_on_ci(monkeypatch, tmp_path, capsys, ci, code):
    """Without chromium, ``caustics setup`` (and ``python -m harness.system``, the
    same command) warns locally (the browser test skips) but fails on CI, where the
    browser test must run."""
    monkeypatch.setattr(system, "ensure_libllvm", lambda install: "/lib/libLLVM.so.19")
    monkeypatch.setattr(system, "CHROMIUM_PATH", str(tmp_path / "absent"))
    monkeypatch.setattr(system.os, "geteuid", lambda: 1000)
    monkeypatch.setenv("CI", ci)
    assert main(["setup"]) == code
    err = capsys.readouterr().err
    assert "apt-get install -y chromium" in err
    assert err.startswith("error: " if code else "warning: ")
    assert system.main([]) == code


@pytest.mark.parametrize(("cuda", "code"), [(False, 1), (True, 0)])
def test_setup_without_libllvm_fails_unless_a_cuda_device_is_present(monkeypatch, capsys,
                                                                     cuda, code):
    """Regression lock: without libLLVM, set-up fails, except where a CUDA device is
    present: Mitsuba then traces on cuda_ad_rgb, and the warning says llvm_ad_rgb is
    unavailable."""
    def missing(install):
        raise SystemSetupError("no libLLVM; run: apt-get install -y libllvm19")

    monkeypatch.setattr(system, "ensure_libllvm", missing)
    monkeypatch.setattr(system, "cuda_device_present", lambda: cuda)
    monkeypatch.setattr(system, "ensure_chromium", lambda install: "/usr/bin/chromium")
    assert main(["setup"]) == code
    err = capsys.readouterr().err
    assert "apt-get install -y libllvm19" in err
    assert ("llvm_ad_rgb is unavailable" in err) == cuda


def test_setup_check_installs_nothing(monkeypatch, capsys):
    """``caustics setup --check`` looks and reports, and never installs, even as root."""
    _no_libllvm(monkeypatch)
    monkeypatch.setattr(system, "CHROMIUM_PATH", "/nonexistent/chromium")
    monkeypatch.setattr(system.os, "geteuid", lambda: 0)
    monkeypatch.setattr(system.shutil, "which", lambda name: "/usr/bin/apt-get")
    monkeypatch.setattr(system, "_apt_install", lambda package: pytest.fail("installed"))
    monkeypatch.setattr(system, "cuda_device_present", lambda: False)
    assert main(["setup", "--check"]) == 1
    assert "libllvm19" in capsys.readouterr().err


def test_loading_mitsuba_without_libllvm_raises_naming_setup_and_installs_nothing(
        monkeypatch):
    """Physical requirement of a library: first use of the Mitsuba runtime where no
    libLLVM is found (and no CUDA device) raises LibLLVMNotFoundError naming
    ``caustics setup`` and the manual command, even as root with apt-get on the
    path; no process is started and the set-up step's installer is never reached."""
    started = []

    def refuse(*args, **kwargs):
        started.append(args)
        raise AssertionError(f"a process was started: {args}")

    for name in ("run", "Popen", "call", "check_call", "check_output"):
        monkeypatch.setattr(subprocess, name, refuse)
    monkeypatch.setattr(os, "system", refuse)
    monkeypatch.setattr(system, "_apt_install", refuse)
    monkeypatch.setattr(os, "geteuid", lambda: 0)
    monkeypatch.delenv(_mi.VARIANT_ENV, raising=False)
    monkeypatch.delenv("DRJIT_LIBLLVM_PATH", raising=False)
    monkeypatch.setattr(_mi, "find_libllvm", lambda: None)
    monkeypatch.setattr(llvm, "find_libllvm", lambda: None)
    monkeypatch.setattr(_mi, "cuda_device_present", lambda: False)
    # The uncached body of load(): a cached result from another test is not a load.
    with pytest.raises(llvm.LibLLVMNotFoundError) as info:
        _mi.load.__wrapped__()
    message = str(info.value)
    assert "caustics setup" in message
    assert "apt-get install -y libllvm19" in message and "DRJIT_LIBLLVM_PATH=" in message
    assert started == []
    assert "DRJIT_LIBLLVM_PATH" not in os.environ
