"""Methods: named renderers that the harness compares with the reference.

A **method** turns a :class:`scenes.Scene` (its settings included) into a
:class:`renderers.results.RenderResult` in the radiometric contract (docs/architecture.md):
a camera image in W m^-2 sr^-1 and one receiver irradiance map in W/m^2 per
receiver, over the receiver's (u, v) extent. Methods are entry points of the group
``caustics_harness.methods``; the caustics-mapping presets ``paper`` and ``strong``
are registered there by this project, and a third-party package registers its own
the same way (``[project.entry-points."caustics_harness.methods"]``), after which
``caustics compare SCENE --method NAME`` compares it without any change here.

The entry point names an object with the :class:`Method` protocol, or a class or
other callable without arguments that returns one.

Every method is rendered through its protocol's :meth:`Method.render`, the presets
too. A method that renders with the caustics-mapping renderer may also have the
capability :class:`GLMethod` ("has a GL runner"): :meth:`GLMethod.in_context` gives
the same method rendering in a GL context and on meshes that the caller holds, so
that the harness renders it, and the caustics-mapping studies render its settings,
in one context (``harness.studies.runner.RealtimeRunner``).
"""

from __future__ import annotations

from importlib.metadata import entry_points
from typing import Any, Protocol, runtime_checkable

from renderers.results import RenderResult
from scenes import Scene
from scenes.errors import HarnessError

__all__ = ["GROUP", "ExternalMethod", "GLMethod", "Method", "MethodError", "available_methods",
           "has_gl_runner", "load_method", "renders_elsewhere"]

#: The entry-point group methods register in.
GROUP = "caustics_harness.methods"


class MethodError(HarnessError, LookupError):
    """A method name is not registered, or its entry point is not a method."""


@runtime_checkable
class Method(Protocol):
    """The protocol of a method.

    Attributes
    ----------
    name : str
        The name it is registered under.
    description : str
        One line for reports.
    """

    name: str
    description: str

    def configure(self, scene: Scene) -> Scene:
        """The scene with this method's settings applied (recorded in the report)."""
        ...

    def render(self, scene: Scene) -> RenderResult:
        """Render ``scene`` (as returned by :meth:`configure`)."""
        ...


@runtime_checkable
class GLMethod(Method, Protocol):
    """The capability of a method with a GL runner: it renders with the
    caustics-mapping renderer, at the settings its :meth:`~Method.configure` gives
    the scene, and can do so in a GL context that the caller holds.

    The harness then renders it in one context for the warm-up and every timed
    render, and the caustics-mapping studies (convergence, cost, decomposition)
    apply to it: they render its configured scene under other settings in that
    context (``harness.studies.runner.RealtimeRunner``) and so describe this method.
    """

    def in_context(self, ctx: Any, *, geometry: Any = None) -> GLMethod:
        """This method, its :meth:`~Method.render` drawing in ``ctx`` (a moderngl
        context the caller made and releases) on ``geometry`` (the
        :class:`scenes.geometry.SceneGeometry` of the scenes it is given; None: built
        per render)."""
        ...


@runtime_checkable
class ExternalMethod(Method, Protocol):
    """The capability of a method whose images were rendered outside the harness
    (read from files): the harness cannot time it. Its :meth:`~Method.render` is
    called once and never timed; the time its renderer reported, if any, is carried
    as reported (:meth:`reported_timing`), labelled as not measured by the harness.
    """

    def reported_timing(self) -> dict | None:
        """What the external renderer reported of its own time (``frame_ms`` in ms,
        optionally ``device`` and other keys), or None when it reported nothing."""
        ...


def renders_elsewhere(method: Method) -> bool:
    """Whether ``method`` has the capability :class:`ExternalMethod`."""
    return isinstance(method, ExternalMethod)


def has_gl_runner(method: Method) -> bool:
    """Whether ``method`` has the capability :class:`GLMethod`."""
    return isinstance(method, GLMethod)


def available_methods() -> tuple[str, ...]:
    """Names of every registered method, sorted."""
    return tuple(sorted({ep.name for ep in entry_points(group=GROUP)}))


def load_method(name: str) -> Method:
    """The method registered as ``name``.

    Raises
    ------
    MethodError
        No such method (the message lists the registered ones), or the entry point
        does not give an object with the :class:`Method` protocol.
    """
    found = [ep for ep in entry_points(group=GROUP) if ep.name == name]
    if not found:
        known = ", ".join(available_methods()) or "none"
        raise MethodError(f"unknown method {name!r} (registered in {GROUP}: {known})")
    target = found[0].load()
    if isinstance(target, type) or (callable(target) and not isinstance(target, Method)):
        target = target()                   # a class or factory: call it for the method
    method = target
    if not isinstance(method, Method):
        raise MethodError(f"entry point {found[0].value!r} of method {name!r} is not a "
                          "method (needs name, description, configure, render)")
    return method
