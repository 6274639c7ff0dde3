"""A sweep expanded into what it computes: rows and references, each with its key.

Rows: every scene × method × combination of the grid, in that order. Each row's
scene is the scene file's with the reference budget (``[sweep.reference]``), the
fixed settings (``[sweep.settings]``) and the row's setting applied, then
configured by the method (a preset fills the settings left unset).

References: every row of a scene whose reference settings agree (all of them,
unless the grid varies ``receiver_map`` or ``all_specular_paths``) shares one
reference and one independent reference on the next K seeds (the noise floor), as
``caustics compare`` renders them; each is keyed by
:func:`renderers.mitsuba.cache.cache_key`, so the sweep and ``compare`` share
cache entries.

A row's key (:func:`row_key`) is the SHA-256 of everything its result depends on:
the keys of both references (the scene's physics, meshes, reference settings,
Mitsuba and Dr.Jit versions), the method (name, entry point, the version of the
distribution that provides it), the row's full settings after the method configured
them, the scene's name and description (its page shows them), ``repeats``, and
:data:`ROW_FORMAT`. What it cannot see is a change to the code of an installed
version (an editable install): ``--no-cache`` recomputes.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass
from importlib.metadata import PackageNotFoundError, entry_points, version

from harness.sweep.spec import Setting, Sweep
from renderers.methods import GROUP, load_method
from renderers.mitsuba.cache import cache_key
from reports import scene_folder
from scenes import Scene, with_settings
from scenes.files import jsonable

__all__ = ["ROW_FORMAT", "ReferenceJob", "RowJob", "SweepPlan", "method_identity",
           "plan_sweep", "row_key"]

#: Bump when what a row computes, or the entry's layout, changes meaning.
ROW_FORMAT = 2


@dataclass(frozen=True)
class ReferenceJob:
    """One reference to trace: K seed tasks and a merge.

    Attributes
    ----------
    key : str
        Its reference-cache key.
    scene : Scene
        A scene carrying its settings (seed, seeds, photons, ...).
    role : str
        ``reference`` or ``independent`` (the noise floor, seeds seed+K ..).
    """

    key: str
    scene: Scene
    role: str

    @property
    def seeds(self) -> tuple[int, ...]:
        s = self.scene.settings
        return tuple(range(s.seed, s.seed + s.seeds))


@dataclass(frozen=True)
class RowJob:
    """One (scene, method, setting) row.

    Attributes
    ----------
    scene : Scene
        Configured by the method: what renders.
    method : str
    setting : Setting
    key : str
        Results-cache key (:func:`row_key`).
    folder : str
        Its page's folder in the output.
    reference, independent : str
        Keys of its :class:`ReferenceJob` s.
    """

    scene: Scene
    method: str
    setting: Setting
    key: str
    folder: str
    reference: str
    independent: str


@dataclass(frozen=True)
class SweepPlan:
    """Rows in order, and the references they need (by key)."""

    sweep: Sweep
    rows: tuple[RowJob, ...]
    references: dict[str, ReferenceJob]
    versions: dict


def method_identity(name: str) -> dict:
    """Name, entry point and the providing distribution's version of a method."""
    for ep in entry_points(group=GROUP):
        if ep.name == name:
            dist = ep.dist
            return {"name": name, "entry_point": ep.value,
                    "distribution": dist.metadata["Name"] if dist else None,
                    "version": dist.version if dist else None}
    return {"name": name}


def _harness_version() -> str:
    try:
        return version("caustics-harness")
    except PackageNotFoundError:
        return "unknown"


def row_key(scene: Scene, method: dict, *, reference: str, independent: str,
            repeats: int) -> str:
    """Hex SHA-256 naming a row's result (see the module docstring)."""
    document = {"format": ROW_FORMAT, "harness": _harness_version(), "method": method,
                "settings": jsonable(asdict(scene.settings)),
                "scene": {"name": scene.name, "description": scene.info.description},
                "reference": reference, "independent": independent, "repeats": repeats}
    return hashlib.sha256(json.dumps(document, sort_keys=True).encode()).hexdigest()


def plan_sweep(sweep: Sweep, *, versions: dict) -> SweepPlan:
    """Expand ``sweep`` (see the module docstring); ``versions`` are Mitsuba's and
    Dr.Jit's (``renderers.mitsuba._mi.versions()``), part of every reference key."""
    methods = {name: (load_method(name), method_identity(name)) for name in sweep.methods}
    rows, references, taken = [], {}, []
    for base in sweep.scenes:
        for name, (method, identity) in methods.items():
            for setting in sweep.combinations():
                scene = method.configure(sweep.scene_for(base, setting))
                s = scene.settings
                independent = with_settings(scene, {"seed": s.seed + s.seeds})
                keys = []
                for role, ref_scene in (("reference", scene), ("independent", independent)):
                    key = cache_key(ref_scene, versions)
                    references.setdefault(key, ReferenceJob(key, ref_scene, role))
                    keys.append(key)
                folder = scene_folder("-".join(p for p in (scene.name, name, setting.slug) if p),
                                      taken=taken)
                taken.append(folder)
                rows.append(RowJob(scene=scene, method=name, setting=setting,
                                   key=row_key(scene, identity, reference=keys[0],
                                               independent=keys[1], repeats=sweep.repeats),
                                   folder=folder, reference=keys[0], independent=keys[1]))
    return SweepPlan(sweep=sweep, rows=tuple(rows), references=references, versions=versions)
