"""The receivers' maps scored where their triangles went to a finer atlas: each
coarse texel plus the mean of the finer texels over it, summed on the GL side
(``scored_maps``). A triangle's finer texel values are its integrals over each of
them, so this is the only way its flux reaches the scored map: a wrong block, a
missed slot or a lost factor changes the flux the harness scores.
"""

from __future__ import annotations

import numpy as np
import pytest

from renderers.caustics_mapping.context import pool
from renderers.caustics_mapping.scored_maps import scored_maps
from renderers.caustics_mapping.splat_maps import read_rgba


def _upload(ctx, values: np.ndarray):
    """A pooled RGBA32F texture holding ``values`` ((H, W, 4), row 0 at the bottom)."""
    texture = pool(ctx).texture((values.shape[1], values.shape[0]))
    texture.write(np.ascontiguousarray(values, np.float32).tobytes())
    return texture


@pytest.mark.physical_requirement
@pytest.mark.parametrize("factor", [2, 3])
def test_each_texel_is_coarse_plus_the_mean_of_its_finer_block(ctx, factor, record_property):
    """Three slots of 8 x 5 texels, random values spanning six decades (a focus next
    to a faint halo): every scored texel, all four channels, equals the coarse
    texel plus the mean of its factor x factor finer texels, to float32 rounding
    (bound 1e-6 of the value: four to nine additions and one division in float32)."""
    rng = np.random.default_rng(7)
    h, w = 5, 3 * 8
    coarse = 10.0 ** rng.uniform(-3, 3, (h, w, 4))
    fine = 10.0 ** rng.uniform(-3, 3, (factor * h, factor * w, 4))
    # A pooled framebuffer keeps the viewport and scissor a splat pass left on it: the
    # pass must write the whole atlas whatever the texture's framebuffer last had.
    coarse_texture, fine_texture = _upload(ctx, coarse), _upload(ctx, fine)
    stale = pool(ctx).texture((w, h))
    pool(ctx).framebuffer([stale]).viewport = (16, 0, 8, h)    # the last slot only
    pool(ctx).give_back(stale)
    scored = scored_maps(ctx, coarse_texture, fine_texture, factor=factor)
    assert scored is stale          # the pool handed the same texture back
    got = read_rgba(scored)
    expected = coarse + fine.reshape(h, factor, w, factor, 4).mean(axis=(1, 3))
    record_property("checks", 1)
    np.testing.assert_allclose(got, expected, rtol=1e-6)


def test_a_finer_atlas_of_another_size_is_refused(ctx):
    """Bad input: a finer atlas that is not ``factor`` times the coarse one per side
    is named in a ValueError, not averaged over the wrong blocks."""
    coarse = _upload(ctx, np.zeros((4, 8, 4)))
    fine = _upload(ctx, np.zeros((8, 12, 4)))
    with pytest.raises(ValueError, match="not 2 x"):
        scored_maps(ctx, coarse, fine, factor=2)
