"""``python -m harness`` is the ``caustics`` command."""

from harness.cli import run

run()
