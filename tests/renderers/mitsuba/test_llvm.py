"""Dr.Jit's libLLVM is found and set explicitly, or its absence is a typed error
naming the set-up step (never an install); a CUDA variant needs none."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from renderers.mitsuba import llvm


def test_found_library_is_configured(monkeypatch):
    """On this machine (tox's set-up step installs libllvm19 first) the path is set
    explicitly."""
    monkeypatch.delenv("DRJIT_LIBLLVM_PATH", raising=False)
    path = llvm.configure_drjit()
    assert os.path.isfile(path) and "19" in os.path.basename(path)
    assert os.environ["DRJIT_LIBLLVM_PATH"] == path


def test_preset_path_is_honoured(monkeypatch, tmp_path):
    lib = tmp_path / "libLLVM.so.99"
    lib.write_bytes(b"")
    monkeypatch.setenv("DRJIT_LIBLLVM_PATH", str(lib))
    assert llvm.find_libllvm() == str(lib)


def test_missing_library_names_the_setup_step(monkeypatch):
    """Without the library the error names ``caustics setup``, the apt command and
    the variable to set; a stale DRJIT_LIBLLVM_PATH is named too."""
    monkeypatch.setenv("DRJIT_LIBLLVM_PATH", "/nonexistent/libLLVM.so.19.1")
    monkeypatch.setattr(llvm, "LLVM_GLOBS", ("/nonexistent/libLLVM.so.19*",))
    with pytest.raises(llvm.LibLLVMNotFoundError) as info:
        llvm.configure_drjit()
    message = str(info.value)
    assert "`caustics setup`" in message
    assert "apt-get update && apt-get install -y libllvm19" in message
    assert f"DRJIT_LIBLLVM_PATH={llvm.DEBIAN_LIBLLVM}" in message
    assert "DRJIT_LIBLLVM_PATH=/nonexistent/libLLVM.so.19.1 is not a file" in message


#: Loads Mitsuba with the libLLVM set-up replaced by a failure (and, with argument
#: ``auto``, as on a GPU machine without libLLVM: none found, a CUDA device reported).
_LOAD_WITHOUT_LIBLLVM = """
import sys
import renderers.mitsuba._mi as m
def asked():
    raise AssertionError("libLLVM was asked for")
m.configure_drjit = asked
if sys.argv[1:] == ["auto"]:
    m.find_libllvm = lambda: None
    m.cuda_device_present = lambda: True
try:
    print("loaded", m.load()[2])
except m.MitsubaError as error:
    print("refused", error)
"""


def test_forced_cuda_variant_asks_for_no_libllvm():
    """Regression lock: with ``CAUSTICS_MITSUBA_VARIANT=cuda_ad_rgb`` Mitsuba loads
    without looking for libLLVM. A GPU machine that is offline and has no libLLVM
    can still trace on CUDA. Here there is no CUDA device, so Mitsuba refuses the
    variant with MitsubaError, which names it; on a GPU machine the variant loads.
    Run in a fresh process, so this process's variant stays as it is."""
    env = {k: v for k, v in os.environ.items() if k != "DRJIT_LIBLLVM_PATH"}
    env["CAUSTICS_MITSUBA_VARIANT"] = "cuda_ad_rgb"
    proc = subprocess.run([sys.executable, "-c", _LOAD_WITHOUT_LIBLLVM], env=env, text=True,
                          capture_output=True, timeout=300, check=False)
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout.strip().splitlines()[-1]
    assert out == "loaded cuda_ad_rgb" or out.startswith(
        "refused CAUSTICS_MITSUBA_VARIANT=cuda_ad_rgb: Mitsuba cannot use this variant")


def test_choice_by_device_asks_for_no_libllvm_where_none_is_found_beside_cuda():
    """Regression lock: with no variant forced, where no libLLVM is found and the
    driver reports a CUDA device (both faked here), Mitsuba loads without the
    libLLVM set-up, which would install or fail. Dr.Jit then finds no CUDA device
    here and takes llvm_ad_rgb, through the DRJIT_LIBLLVM_PATH the environment
    already has; on a GPU machine it takes cuda_ad_rgb."""
    env = {k: v for k, v in os.environ.items() if k != "CAUSTICS_MITSUBA_VARIANT"}
    env.setdefault("DRJIT_LIBLLVM_PATH", llvm.find_libllvm() or "")
    proc = subprocess.run([sys.executable, "-c", _LOAD_WITHOUT_LIBLLVM, "auto"], env=env, text=True,
                          capture_output=True, timeout=300, check=False)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().splitlines()[-1] in ("loaded llvm_ad_rgb", "loaded cuda_ad_rgb")


def test_no_cuda_device_where_the_driver_library_is_missing(monkeypatch):
    """Regression lock of the probe: without libcuda.so.1 there is no CUDA
    device (and nothing is raised)."""
    def no_library(name):
        raise OSError(f"{name}: cannot open shared object file")

    monkeypatch.setattr(llvm.ctypes, "CDLL", no_library)
    assert llvm.cuda_device_present() is False
