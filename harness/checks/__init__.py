"""Accuracy checks of three kinds, named as such everywhere (files, test ids, the
report, the ``compare`` summary and the pytest summary):

* **physical requirements** (:mod:`harness.checks.physical`): independent of the
  method's output being right: the reference against analytic answers
  (:mod:`harness.checks.analytic`), energy, flux agreement, finite values, no light
  trapped where none can be; each constant carries its derivation;
* **method targets** (:mod:`harness.checks.targets`, ``data/method_targets.toml``):
  what a method should reach on a scene, with the reason for the number; a target
  missed today carries its gap and is reported as a known gap (an ``xfail``);
* **regression locks** (:mod:`harness.checks.locks`, ``data/regression_locks.toml``):
  calibrated from today's output against the golden references; they guard against
  change, not accuracy.

The golden references (:mod:`harness.checks.golden`: 128² receiver maps with
per-texel variance, SHA-256 manifest), checked with a per-pixel Z-test
(:mod:`harness.checks.ztest`), and the three files ship inside this package
(``data/``), so every default path comes from the installed package, never from the
working directory.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["GAPS_FILE", "GOLDEN_DIR", "KINDS", "LOCK", "LOCKS_FILE", "PHYSICAL", "TARGET",
           "TARGETS_FILE"]

_DATA = Path(str(resources.files("harness.checks") / "data"))
#: Bundled golden references (``manifest.json`` and ``<scene>/receiver<i>.exr``).
GOLDEN_DIR = _DATA / "golden"
#: Bundled regression locks, checked against :data:`GOLDEN_DIR`.
LOCKS_FILE = _DATA / "regression_locks.toml"
#: Bundled method targets.
TARGETS_FILE = _DATA / "method_targets.toml"
#: Bundled known gaps of the physical requirements.
GAPS_FILE = _DATA / "known_gaps.toml"

PHYSICAL, TARGET, LOCK = "physical requirement", "method target", "regression lock"
#: The three kinds, in the order every output lists them.
KINDS = (PHYSICAL, TARGET, LOCK)
