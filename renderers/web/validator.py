"""The Khronos glTF validator (npm ``gltf-validator``), run by Node on one file.

The project's JavaScript workspace is this folder (``package.json``, its lockfile, and
``node_modules/`` after ``npm ci --prefix renderers/web``); ``validate.mjs`` prints the
validator's JSON report, whose ``issues`` count messages by severity: errors (0),
warnings (1), infos (2), hints (3).
"""

from __future__ import annotations

import json
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

from scenes.errors import HarnessError

__all__ = ["SCRIPT", "WORKSPACE", "ValidationReport", "ValidatorError", "unavailable_reason",
           "validate_gltf"]

#: The JavaScript workspace (``npm ci --prefix`` this folder).
WORKSPACE = Path(__file__).resolve().parent
#: The Node script that validates one file.
SCRIPT = WORKSPACE / "validate.mjs"
_INSTALL = "npm ci --prefix renderers/web"


class ValidatorError(HarnessError):
    """The validator could not run (no Node, no ``node_modules``) or refused the file."""


@dataclass(frozen=True)
class ValidationReport:
    """The validator's verdict on one file.

    Attributes
    ----------
    path : Path
    errors, warnings, infos, hints : int
        Issues of each severity.
    messages : tuple of dict
        Every issue: ``code``, ``message``, ``severity`` (0 error .. 3 hint), ``pointer``.
    report : dict
        The validator's whole JSON report.
    """

    path: Path
    errors: int
    warnings: int
    infos: int
    hints: int
    messages: tuple[dict, ...]
    report: dict

    def describe(self, severity: int = 1) -> str:
        """One line per issue of ``severity`` or worse (0 errors only, 1 with warnings)."""
        return "\n".join(f"{m['code']} at {m.get('pointer', '?')}: {m['message']}"
                         for m in self.messages if m["severity"] <= severity)


def unavailable_reason() -> str | None:
    """Why the validator cannot run here (no ``node`` on PATH, or the workspace's
    packages not installed), or None."""
    if shutil.which("node") is None:
        return "Node.js is not installed (node is not on PATH)"
    if not (WORKSPACE / "node_modules" / "gltf-validator").is_dir():
        return f"the JavaScript workspace's packages are not installed: run `{_INSTALL}`"
    return None


def validate_gltf(path: str | Path, *, timeout: float = 120.0) -> ValidationReport:
    """Validate a ``.glb`` or ``.gltf`` (its buffers beside it).

    Raises
    ------
    ValidatorError
        Node or the workspace's packages are missing, the validator ran past
        ``timeout`` seconds, or it refused the file (unreadable, not glTF at all).
    """
    path = Path(path)
    reason = unavailable_reason()
    if reason:
        raise ValidatorError(f"cannot validate {path}: {reason}")
    try:
        done = subprocess.run(["node", str(SCRIPT), str(path)], capture_output=True,
                              text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        raise ValidatorError(f"{path}: the glTF validator ran past {timeout:g} s") from None
    if done.returncode != 0:
        raise ValidatorError(f"{path}: the glTF validator failed: {done.stderr.strip()}")
    report = json.loads(done.stdout)
    issues = report["issues"]
    return ValidationReport(
        path=path, errors=int(issues["numErrors"]), warnings=int(issues["numWarnings"]),
        infos=int(issues["numInfos"]), hints=int(issues["numHints"]),
        messages=tuple(issues["messages"]), report=report,
    )
