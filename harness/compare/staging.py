"""A run's outputs appear all at once: written into a staging folder beside ``-o``
and swapped in at the end.

The staging folder is a hidden sibling (``.<name>.staging-XXXX``), so it is on the
same file system and the swap is two renames: the old folder aside
(``.<name>.old-XXXX``), the staging folder in, then the old one deleted. A run
interrupted before the swap leaves the old output exactly as it was (and removes
its staging folder); a reader never sees one run's pages beside another's JSON.

Only a folder this tool wrote (it holds :data:`MARKER`), an empty one or a missing
one is replaced: ``-o`` pointing at a folder of other files must never delete them,
so there the run writes in place, as before, with a warning.

A run killed outright (SIGKILL, power loss) cannot clean up: the next run into the
same ``-o`` deletes staging and old folders of that name older than
:data:`STALE_SECONDS` (younger ones may belong to a run still going).
"""

from __future__ import annotations

import contextlib
import os
import secrets
import shutil
import time
from collections.abc import Iterator
from pathlib import Path

from harness.terminal import warn
from scenes.errors import HarnessError
from scenes.files import atomic_write_bytes, make_temporary_folder

__all__ = ["MARKER", "SwapError", "staged_output"]

#: Written into every staged output: the folder may be replaced by the next run.
MARKER = ".caustics-output"
#: Age after which a left-over staging or old folder is taken for a killed run's.
STALE_SECONDS = 24 * 3600


class SwapError(HarnessError):
    """The finished output could not be swapped in; it is kept in the staging folder."""


def _replaceable(out_dir: Path) -> bool:
    if not out_dir.exists():
        return True
    if not out_dir.is_dir():
        return False
    return (out_dir / MARKER).is_file() or not any(out_dir.iterdir())


def _remove_stale(out_dir: Path) -> None:
    """Delete ``.<name>.staging-*`` and ``.<name>.old-*`` siblings of ``out_dir`` older
    than STALE_SECONDS that this tool wrote (they hold MARKER)."""
    now = time.time()
    for pattern in (f".{out_dir.name}.staging-*", f".{out_dir.name}.old-*"):
        for leftover in out_dir.parent.glob(pattern):
            with contextlib.suppress(OSError):
                if ((leftover / MARKER).is_file()
                        and now - leftover.stat().st_mtime > STALE_SECONDS):
                    shutil.rmtree(leftover, ignore_errors=True)


def _swap(staging: Path, out_dir: Path) -> None:
    """Old folder aside, staging in, old folder deleted."""
    old = None
    try:
        if out_dir.exists():
            old = out_dir.with_name(f".{out_dir.name}.old-{secrets.token_hex(4)}")
            os.rename(out_dir, old)
        os.rename(staging, out_dir)
    except OSError as error:
        if old is not None and not out_dir.exists():
            with contextlib.suppress(OSError):
                os.rename(old, out_dir)  # put the old output back
        raise SwapError(f"cannot move the new output into {out_dir} ({error.strerror}); "
                        f"it is complete in {staging}") from error
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
        if old.exists():
            warn(f"could not delete the previous output {old}")


@contextlib.contextmanager
def staged_output(out_dir: str | os.PathLike) -> Iterator[Path]:
    """Yield the folder to write a run's outputs into; on a normal exit it becomes
    ``out_dir`` (see the module docstring). On an exception (an interrupt too) the
    staging folder is removed and ``out_dir`` is left untouched.

    Falls back to yielding ``out_dir`` itself (writing in place, with a warning)
    when it holds files this tool did not write or no sibling can be created.
    """
    # A link to a folder: stage beside its target (same file system), keep the link.
    out_dir = Path(out_dir).resolve()
    if not _replaceable(out_dir):
        warn(f"{out_dir} holds files this tool did not write: writing into it in place "
             "(no staging; an interrupted run may leave it mixed)")
        out_dir.mkdir(parents=True, exist_ok=True)
        yield out_dir
        return
    try:
        out_dir.parent.mkdir(parents=True, exist_ok=True)
        _remove_stale(out_dir)
        # The output gets the mode a plain mkdir would give it, not mkdtemp's 0700.
        staging = make_temporary_folder(out_dir.parent, f".{out_dir.name}.staging-")
    except OSError as error:
        warn(f"cannot create a staging folder beside {out_dir} ({error.strerror}): "
             "writing into it in place")
        out_dir.mkdir(parents=True, exist_ok=True)
        yield out_dir
        return
    try:
        atomic_write_bytes(staging / MARKER, b"written by caustics; replaced by the next run\n")
        yield staging
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    _swap(staging, out_dir)
