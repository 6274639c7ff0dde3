"""NumPy mirror of the shader's intersection estimators (``caustic_trace.glsl``).

It works on the receiver positions atlas read back from the GPU and the (v, r) the
shader used, and repeats the shader's arithmetic in float32 step by step (the same
lookups, nearest or bilinear within one receiver, the same start, update rules and
safeguard), so tests can hold the shader to the same numbers: bit for bit with
nearest lookups away from texel borders, and within a stated tolerance with
bilinear ones (the GPU's ``mix`` and the mirror's may round differently). See the
shader header for the equations.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["MapLookup", "MirrorResult", "estimate_distances"]

_F = np.float32
HIT, LOST, DIVERGED = 1, 2, 4


@dataclass(frozen=True, eq=False)
class MapLookup:
    """T(x): the receiver positions atlas and the views that address it.

    Attributes
    ----------
    atlas : ndarray (size, views * size, 4) float32
        Row 0 at the bottom (texel y = 0): xyz world position (m), w receiver + 1.
    view_projs : ndarray (views, 4, 4)
        World -> clip per view (row-major, column vectors).
    size : int
        Texels per view side.
    cube : bool
        Six cube faces chosen by the major axis of x - light_position.
    light_position : ndarray (3,)
    slots : ndarray (6,) int, optional
        Atlas slot of each view, -1 where the view is not stored (default: view i in
        slot i).
    rect : tuple of float, optional
        (x0, x1, y0, y1) of the views on the view plane: tangents (perspective) or
        metres (orthographic), the shader's ``u_map_rect``; needed only for
        :meth:`texel_width`.
    perspective : bool
        Perspective views (point and spot lights) or orthographic (directional).
    """

    atlas: np.ndarray
    view_projs: np.ndarray
    size: int
    cube: bool
    light_position: np.ndarray
    slots: np.ndarray | None = None
    rect: tuple[float, float, float, float] | None = None
    perspective: bool = True

    def texel_width(self, x: np.ndarray) -> np.ndarray:
        """Width (m) of one texel at points x (K, 3), float32: the view-plane texel
        width times the distance from the light (perspective) or the texel width
        (orthographic); ``map_texel_width`` in ``common.glsl``."""
        if self.rect is None:
            raise ValueError("texel_width needs the views' rect")
        x0, x1, y0, y1 = self.rect
        w = _F(max(x1 - x0, y1 - y0)) / _F(self.size)
        if not self.perspective:
            return np.full(len(x), w, _F)
        return (w * _norm(x.astype(_F) - self.light_position.astype(_F))).astype(_F)

    def locate(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(face, atlas texel (K, 2) as x, y, inside) for points x (K, 3)."""
        face, texel, ok, _ = self.locate_with_margin(x)
        return face, texel, ok

    def locate_with_margin(self, x: np.ndarray):
        """:meth:`locate` plus each point's distance to the nearest texel border
        (texels): below ~1e-4 the shader's rounding may pick the neighbour."""
        face, texel, ok, margin, _ = self._project(x)
        return face, texel, ok, margin

    def _project(self, x: np.ndarray):
        """(face, texel, inside, margin, face pixel coordinates (K, 2))."""
        x = x.astype(_F)
        if self.cube:
            d = x - self.light_position.astype(_F)
            a = np.abs(d)
            face = np.where(
                (a[:, 0] >= a[:, 1]) & (a[:, 0] >= a[:, 2]), np.where(d[:, 0] >= 0, 0, 1),
                np.where(a[:, 1] >= a[:, 2], np.where(d[:, 1] >= 0, 2, 3),
                         np.where(d[:, 2] >= 0, 4, 5)))
        else:
            face = np.zeros(len(x), np.int64)
        m = self.view_projs.astype(_F)[face]                      # (K, 4, 4)
        xh = np.concatenate([x, np.ones((len(x), 1), _F)], axis=1)
        clip = np.einsum("kij,kj->ki", m, xh).astype(_F)
        w = clip[:, 3]
        ok = w > 0
        safe_w = np.where(ok, w, _F(1))
        ndc = (clip[:, :2] / safe_w[:, None]).astype(_F)
        ok &= np.all(np.abs(ndc) <= 1, axis=1)
        slots = np.arange(6) if self.slots is None else np.asarray(self.slots)
        slot = slots[face]
        ok &= slot >= 0
        pixel = (ndc * _F(0.5) + _F(0.5)) * _F(self.size)
        t = np.floor(pixel)
        margin = np.min(np.minimum(pixel - t, t + 1 - pixel), axis=1)
        t = np.clip(np.where(ok[:, None], t, 0), 0, self.size - 1).astype(np.int64)
        texel = np.stack([np.maximum(slot, 0) * self.size + t[:, 0], t[:, 1]], axis=1)
        return face, texel, ok, np.where(ok, margin, np.inf), (pixel, np.maximum(slot, 0))

    def receiver_at(self, x: np.ndarray, margin: np.ndarray | None = None, *,
                    filtered: bool = False):
        """T(x) (K, 3) float32 and whether a receiver is there (K,); ``margin``, if
        given, is lowered in place to each point's texel-border distance.

        ``filtered``: bilinear between the four texels around x when they all show
        the same receiver, else nearest (``bilinear_at`` in ``common.glsl``).
        """
        _, texel, ok, m, (pixel, slot) = self._project(x)
        if margin is not None:
            np.minimum(margin, m, out=margin)
        q = self.atlas[texel[:, 1], texel[:, 0]]
        position = q[:, :3].astype(_F)
        if filtered and self.size >= 2:
            grid = np.clip(pixel - _F(0.5), 0, self.size - 1).astype(_F)
            i0 = np.minimum(np.floor(grid), self.size - 2).astype(np.int64)
            f = (grid - i0).astype(_F)
            x0 = slot * self.size + i0[:, 0]
            y0 = i0[:, 1]
            corners = [self.atlas[y0 + dy, x0 + dx] for dy in (0, 1) for dx in (0, 1)]
            tags = np.stack([c[:, 3] for c in corners])
            same = (tags[0] > 0.5) & np.all(np.abs(tags - tags[0]) < 0.5, axis=0) & ok
            fx, fy = f[:, :1], f[:, 1:]
            low = corners[0][:, :3] * (1 - fx) + corners[1][:, :3] * fx
            high = corners[2][:, :3] * (1 - fx) + corners[3][:, :3] * fx
            blended = (low * (1 - fy) + high * fy).astype(_F)
            position = np.where(same[:, None], blended, position)
        return position, ok & (q[:, 3] > 0.5)


@dataclass(frozen=True, eq=False)
class MirrorResult:
    """history (K, iterations + 1) estimates (m), distance (K,), status (K,), and
    margin (K,): the smallest distance (texels) of any lookup of the vertex to a
    texel border; where it is ~0 the shader may legitimately read the neighbour."""

    history: np.ndarray
    distance: np.ndarray
    status: np.ndarray
    margin: np.ndarray


def _norm(a: np.ndarray) -> np.ndarray:
    return np.sqrt(np.sum(a * a, axis=1, dtype=_F)).astype(_F)


def estimate_distances(
    lookup: MapLookup, origins: np.ndarray, directions: np.ndarray, *, estimator: str,
    iterations: int, eps: float, safeguarded: bool = False, filtered: bool = False,
    start: str = "receiver", start_distance: float = 0.1, converged: float = 0.0,
) -> MirrorResult:
    """Run one estimator on rays (v, r), like the shader does.

    Parameters
    ----------
    origins, directions : ndarray (K, 3)
        v (m) and unit r, as the trace pass wrote them.
    estimator : {"modified", "newton", "secant"}
    iterations : int
        Updates after the start estimate d_1 = g(0) (or ``start_distance``).
    eps : float
        Newton's finite-difference step (m).
    filtered : bool
        Bilinear lookups within one receiver.
    start, start_distance
        ``"receiver"`` (d_1 = g(0)) or ``"fixed"`` (d_1 = ``start_distance``, m).
    converged : float
        An estimate with |h| at most this many positions texels
        (:meth:`MapLookup.texel_width`) at it ends the iterations and is kept
        (``ESTIMATE_TOLERANCE`` in ``estimators.glsl``; the trace pass's
        ``TraceOptions.converged``); 0: only at h = 0.

    Returns
    -------
    MirrorResult
        The final status is HIT, LOST (a lookup, or the final one, found no
        receiver) or DIVERGED (non-finite update, unsafeguarded only).
    """
    v = origins.astype(_F)
    r = directions.astype(_F)
    k_count = len(v)
    eps = _F(eps)

    margin = np.full(k_count, np.inf)

    def g_of(d):
        t, ok = lookup.receiver_at(v + d[:, None] * r, margin, filtered=filtered)
        return _norm(t - v), t, ok

    hist = np.zeros((k_count, iterations + 1), _F)
    if start == "fixed":
        ok0 = np.ones(k_count, bool)
        d = np.full(k_count, _F(start_distance))
        have_prev = np.zeros(k_count, bool)
    else:
        g0, _, ok0 = g_of(np.zeros(k_count, _F))
        d = np.where(ok0, g0, _F(0)).astype(_F)
        have_prev = np.ones(k_count, bool)
    status = np.where(ok0, HIT, LOST)
    d_prev = np.zeros(k_count, _F)
    h_prev = np.where(have_prev, d, _F(0)).astype(_F)
    lo = np.zeros(k_count, _F)
    hi = np.full(k_count, _F(-1))
    # h at the bracket's ends, NaN where unknown (h(0) = g(0) with the receiver start).
    h_lo = np.where(have_prev, d, np.nan).astype(_F)
    h_hi = np.full(k_count, np.nan, _F)
    hist[:, 0] = d
    seen = np.full(k_count, _F(-1) if start == "fixed" else _F(0))
    converged_at = np.zeros(k_count, bool)     # iterations ended at a converged estimate
    for k in range(1, iterations + 1):
        active = (status == HIT) & ~converged_at
        g, t, ok = g_of(d)
        missed = active & ~ok
        if safeguarded:
            # An estimate that sees no receiver overshot its edge: halfway back to
            # the last one that saw one (caustic_trace.glsl).
            back = missed & (seen >= 0)
            new_hi = back & ((hi < 0) | (d < hi))
            hi = np.where(new_hi, d, hi)
            h_hi = np.where(new_hi, _F(np.nan), h_hi)
            d_prev = np.where(back, d, d_prev)
            have_prev &= ~back
            d = np.where(back, _F(0.5) * (seen + d), d).astype(_F)
            missed &= ~back
            active &= ok
        status = np.where(missed, LOST, status)
        active &= ok
        seen = np.where(active, d, seen)
        h = (g - d).astype(_F)
        if converged > 0:
            tol = (_F(converged) * lookup.texel_width(v + d[:, None] * r)).astype(_F)
        else:
            tol = np.zeros(k_count, _F)
        # Converged (|h| within the tolerance): the estimate is kept from here on.
        done = active & (np.abs(h) <= tol)
        converged_at |= done
        active &= ~done
        new_lo = active & (h >= 0) & (d >= lo)
        lo = np.where(new_lo, d, lo)
        h_lo = np.where(new_lo, h, h_lo)
        new_hi = active & (h < 0) & ((hi < 0) | (d <= hi))
        hi = np.where(new_hi, d, hi)
        h_hi = np.where(new_hi, h, h_hi)
        finite = np.ones(k_count, bool)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            if estimator == "modified":
                prop = g
            elif estimator == "secant":
                # Without a previous point (fixed start, or a restart after stepping
                # back) the modified step g.
                den = (h - h_prev).astype(_F)
                finite = (den != 0) | ~have_prev
                secant = d - h * (d - d_prev) / np.where(den != 0, den, 1)
                prop = np.where(have_prev, np.where(den != 0, secant, d), g)
            elif estimator == "newton":
                f = _norm(t - (v + d[:, None] * r))
                de = (d + eps).astype(_F)
                _g2, t2, ok2 = g_of(de)
                lost2 = active & (h != 0) & ~ok2
                status = np.where(lost2, LOST, status)
                active &= ~lost2
                fe = _norm(t2 - (v + de[:, None] * r))
                den = (fe - f).astype(_F)
                finite = (f == 0) | (den != 0)
                step = np.where(den != 0, f * eps / np.where(den != 0, den, 1), 0)
                prop = np.where(f == 0, d, d - step)
            else:
                raise ValueError(f"unknown estimator {estimator!r}")
            prop = np.where(h == 0, d, prop).astype(_F)
            finite = np.where(h == 0, True, finite) & (np.abs(prop) < 1e30)
        if safeguarded:
            osc = (k >= 2) & ((prop - d) * (d - d_prev) < 0) & (
                np.abs(prop - d) >= _F(0.5) * np.abs(d - d_prev))
            # Without an upper bracket end, a step past twice the modified update's
            # distance is a runaway (the caustic_trace.glsl trust region).
            outside = (prop < lo) | np.where(hi >= 0, prop > hi,
                                             prop > _F(2) * np.maximum(g, lo))
            fallback = ~finite | osc | outside
            # The bracket's false-position point where both ends' h are known and it
            # does not itself oscillate, else its midpoint (estimators.glsl).
            known = np.isfinite(h_lo) & np.isfinite(h_hi) & (h_lo > h_hi)
            with np.errstate(divide="ignore", invalid="ignore"):
                falsi = (lo + h_lo * (hi - lo) / np.where(known, h_lo - h_hi, 1)).astype(_F)
            falsi_osc = (k >= 2) & ((falsi - d) * (d - d_prev) < 0) & (
                np.abs(falsi - d) >= _F(0.5) * np.abs(d - d_prev))
            inner = np.where(known & ~falsi_osc, falsi, _F(0.5) * (lo + hi))
            prop = np.where(fallback, np.where(hi >= 0, inner, g), prop)
        else:
            status = np.where(active & ~finite, DIVERGED, status)
            active &= finite
        d_prev = np.where(active, d, d_prev)
        h_prev = np.where(active, h, h_prev)
        d = np.where(active, prop, d).astype(_F)
        have_prev |= active
        hist[:, k] = d
    _, ok = lookup.receiver_at(v + d[:, None] * r, margin, filtered=filtered)
    status = np.where((status == HIT) & ~ok, LOST, status)
    hist = np.where((status == LOST)[:, None] & ~ok0[:, None], _F(0), hist)
    return MirrorResult(hist, d, status.astype(np.int32), margin)
