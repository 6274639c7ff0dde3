"""The reference of an animation: every frame's photon-traced receiver maps, with
common random numbers.

Each frame (a :class:`~scenes.model.Scene`, ``scenes.animation``) is traced by
:func:`.reference.estimate_receivers` with caustic-only emission (the receiver maps
the contract compares; no camera image) on K seeds, the **whole** photon budget
``settings.photons`` per seed (no noise target: frames that stopped after different
numbers of rounds would not share their samples).

Common random numbers. With ``common_random_numbers`` (the default) every frame uses
the same seeds ``seed .. seed + K − 1`` and the same streams (one per round), so
photon j of every frame draws the same random numbers
(:meth:`.photons.PhotonTracer.trace`: a lane's PCG32 is keyed by seed, stream,
channel, launch and lane): where the scene changes little between two frames, the
photon takes nearly the same path in both and lands in nearly the same texel, and
most of the two frames' noise cancels in their difference. A still scene's frames are
then the same estimate, and the reference shows no flicker of its own. Without them,
frame i uses the seeds ``seed + i K .. seed + (i + 1) K − 1`` (independent frames:
their differences carry twice each frame's noise variance).

Cache. Each frame is stored under the reference cache root, in ``frames/KEY.npz``:
the mean caustic irradiance and its variance of the mean per receiver, and a JSON
header (photons, seeds, seconds, versions). KEY is the SHA-256 of the frame's
reference key (:func:`.cache.cache_key`, with this frame's seed) and of this
module's :data:`FORMAT`; the frame's seed is in the key, so a reference sequence,
its independent twin and a sequence without common random numbers never share an
entry. Writes are atomic; an entry that cannot be read back whole is rendered again
(with an :class:`~.cache.InvalidCacheEntryWarning`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import json
import time
import warnings
import zipfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from renderers.mitsuba import _mi
from renderers.mitsuba.cache import InvalidCacheEntryWarning, cache_dir, cache_key, entry_lock
from renderers.mitsuba.reference import estimate_receivers
from renderers.results import ReceiverMap
from scenes import Scene, with_settings
from scenes.files import atomic_write_bytes

__all__ = ["FORMAT", "ReferenceFrame", "frame_seeds", "render_reference_frames"]

#: Bump when a stored frame changes meaning.
FORMAT = "reference-frames-1"
SUBFOLDER = "frames"


@dataclass(frozen=True, eq=False)
class ReferenceFrame:
    """One frame of the reference of an animation.

    Attributes
    ----------
    receivers : tuple of ReceiverMap
        Mean caustic irradiance (W/m², row 0 at vmin) with its variance of the mean
        over the K seeds, one per receiver.
    seed : int
        First of the frame's K seeds.
    seeds : int
        K.
    photons : int
        Photons per seed (per channel pass).
    relative_noise : float
        The largest RMS relative standard error over the receivers' caustic regions.
    seconds : float
        Tracing time, ``time.perf_counter`` (kernel compilation included), when the
        frame was rendered; kept for a cache hit.
    cache : str
        ``"hit"``, ``"miss (...)"`` or ``"off"``.
    """

    receivers: tuple[ReceiverMap, ...]
    seed: int
    seeds: int
    photons: int
    relative_noise: float
    seconds: float
    cache: str


def frame_seeds(seed: int, seeds: int, index: int, *, common_random_numbers: bool) -> int:
    """The first of frame ``index``'s K = ``seeds`` seeds: ``seed`` for every frame
    with common random numbers, else ``seed + index K`` (disjoint per frame)."""
    return seed if common_random_numbers else seed + index * seeds


def _key(frame: Scene, versions: dict[str, str]) -> str:
    digest = hashlib.sha256()
    digest.update(f"{FORMAT}|{cache_key(frame, versions)}".encode())
    return digest.hexdigest()


def _render(frame: Scene) -> ReferenceFrame:
    start = time.perf_counter()
    # target_noise 0: the whole budget on every frame (same rounds, same streams).
    estimate = estimate_receivers(frame, target_noise=0.0, caustic_only=True)
    seconds = time.perf_counter() - start
    return ReferenceFrame(receivers=estimate.caustic, seed=estimate.seed, seeds=estimate.seeds,
                          photons=estimate.photons, relative_noise=estimate.relative_noise,
                          seconds=seconds, cache="off")


def _encode(frame: ReferenceFrame, versions: dict[str, str]) -> bytes:
    header = {"format": FORMAT, "seed": frame.seed, "seeds": frame.seeds,
              "photons": frame.photons, "relative_noise": frame.relative_noise,
              "seconds": frame.seconds, "versions": versions,
              "extents": [list(r.extent) for r in frame.receivers]}
    arrays = {"header": np.frombuffer(json.dumps(header).encode(), np.uint8)}
    for i, rmap in enumerate(frame.receivers):
        arrays[f"irradiance_{i}"] = np.asarray(rmap.irradiance, np.float32)
        arrays[f"variance_{i}"] = np.asarray(rmap.variance, np.float32)
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **arrays)
    return buffer.getvalue()


def _decode(data: Path) -> ReferenceFrame:
    """Read a stored frame; any defect raises ValueError (or an OSError)."""
    with np.load(data, allow_pickle=False) as stored:
        header = json.loads(bytes(stored["header"]).decode())
        if header.get("format") != FORMAT:
            raise ValueError(f"format {header.get('format')!r}, expected {FORMAT}")
        receivers = []
        for i, extent in enumerate(header["extents"]):
            irradiance, variance = stored[f"irradiance_{i}"], stored[f"variance_{i}"]
            if (irradiance.ndim != 3 or irradiance.shape[2] != 3
                    or variance.shape != irradiance.shape):
                raise ValueError(f"receiver {i}: shapes {irradiance.shape}, {variance.shape}")
            if not (np.isfinite(irradiance).all() and np.isfinite(variance).all()):
                raise ValueError(f"receiver {i}: values not finite")
            receivers.append(ReceiverMap(irradiance, tuple(float(x) for x in extent), variance))
    return ReferenceFrame(receivers=tuple(receivers), seed=int(header["seed"]),
                          seeds=int(header["seeds"]), photons=int(header["photons"]),
                          relative_noise=float(header["relative_noise"]),
                          seconds=float(header["seconds"]), cache="hit")


def _cached(frame: Scene, root: Path, versions: dict[str, str]) -> ReferenceFrame:
    key = _key(frame, versions)
    folder = root / SUBFOLDER
    path = folder / f"{key}.npz"
    with entry_lock(folder, key):
        why = "absent"
        if path.exists():
            try:
                return _decode(path)
            except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as error:
                why = f"invalid: {' '.join(str(error).split())}"
                warnings.warn(f"invalid cached reference frame, re-rendering: {path}: {why}",
                              InvalidCacheEntryWarning, stacklevel=3)
        rendered = _render(frame)
        atomic_write_bytes(path, _encode(rendered, versions))
        return dataclasses.replace(rendered, cache=f"miss ({why})")


def render_reference_frames(frames: Sequence[Scene], *, seed: int | None = None,
                            common_random_numbers: bool = True,
                            cache: str | Path | None = None, use_cache: bool = True,
                            progress=None) -> tuple[ReferenceFrame, ...]:
    """The reference of every frame (see the module docstring).

    Parameters
    ----------
    frames : sequence of Scene
        The animation's frames, in order (``scenes.animation.animation_frames``).
    seed : int, optional
        First seed of the sequence; default the first frame's ``settings.seed``.
        K = ``settings.seeds`` and the budget ``settings.photons`` come from each frame.
    common_random_numbers : bool
        The same seeds for every frame (default), or disjoint seeds per frame
        (:func:`frame_seeds`).
    cache, use_cache
        Cache root (default ``$CAUSTICS_CACHE_DIR`` or ~/.cache/caustics-harness/reference)
        and whether to read and write it.
    progress : callable, optional
        Called once after each frame.

    Returns
    -------
    tuple of ReferenceFrame
        One per frame, in order.
    """
    if not frames:
        return ()
    first = frames[0].settings.seed if seed is None else int(seed)
    versions = _mi.versions()
    root = cache_dir(cache)
    out = []
    for index, scene in enumerate(frames):
        start = frame_seeds(first, scene.settings.seeds, index,
                            common_random_numbers=common_random_numbers)
        seeded = with_settings(scene, {"seed": start})
        out.append(_cached(seeded, root, versions) if use_cache else _render(seeded))
        if progress is not None:
            progress()
    return tuple(out)
