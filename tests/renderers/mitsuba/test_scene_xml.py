"""Mitsuba 3 XML export (``renderers/mitsuba/scene_xml.py``): ``mi.load_file`` reads back
the reference's own scene (same triangles, BSDFs, emitter, sensor), Mitsuba renders it as
it renders the dict, and the photon tracer on it gives the reference's receiver
irradiance within noise; the stock file (Mitsuba's own ``dielectric``) loads and renders
in a Mitsuba process that knows nothing of the harness, and where the scene weights by
Fresnel it renders what the reference's BSDF renders.

Kind: physical requirements of the export (the same scene, so the same transport); the
noise comparison uses the LuxCore cross-check's flux ratios (harness.crosscheck) with
their standard errors."""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys

import numpy as np
import pytest

from harness.crosscheck import compare_maps
from renderers.mitsuba import load_mitsuba
from renderers.mitsuba.exporter import export_scene
from renderers.mitsuba.llvm import configure_drjit
from renderers.mitsuba.photons import PhotonTracer
from renderers.mitsuba.scene_xml import (
    CHANNEL_FILES,
    load_scene_xml,
    stock_differences,
    write_scene_xml,
)
from renderers.results import ReceiverMap
from scenes import load_scene, resolve_scene
from scenes.geometry import build_geometry
from tests.conftest import BUNDLED_FILES, bundled_id

#: |z| of a flux ratio that passes: each fails with probability 6e-5 under the normal
#: approximation, so the family of one comparison (total, 7 encircled, the regions: a
#: dozen or so ratios) fails well below 0.1 % of runs.
Z_LIMIT = 4.0


def _values(parameter) -> np.ndarray:
    """A traversed parameter as numbers (a transform by its matrix)."""
    return np.asarray(parameter.matrix if hasattr(parameter, "matrix") else parameter,
                      np.float64)


def _written(tmp_path, name: str):
    scene = load_scene(resolve_scene(name))
    paths = write_scene_xml(scene, tmp_path / name, bsdf="harness")
    channels = [0, 1, 2] if len(paths) == 3 else [None]
    assert [p.name for p in paths] == [CHANNEL_FILES[c] for c in channels]
    loaded = {c: load_scene_xml(p, receivers=len(scene.receivers), objects=len(scene.objects))
              for c, p in zip(channels, paths, strict=True)}
    return scene, loaded


@pytest.mark.parametrize("name", ["glass_sphere", "water_pool", "metal_ring",
                                  "dispersion_sphere"])
def test_loaded_xml_holds_the_references_triangles(tmp_path, name):
    """Positions, faces and receiver (u, v) bit for bit (PLY keeps float32), normals to
    float32 rounding."""
    mi, _, _ = load_mitsuba()
    scene, loaded = _written(tmp_path, name)
    geometry = build_geometry(scene)
    pairs = [(f"receiver_{i}", r.mesh) for i, r in enumerate(geometry.receivers)]
    pairs += [(f"object_{i}", o.mesh) for i, o in enumerate(geometry.objects)]
    for exported in loaded.values():
        shapes = {s.id(): mi.traverse(s) for s in exported.scene.shapes()}
        for key, mesh in pairs:
            params = shapes[key]
            np.testing.assert_array_equal(np.asarray(params["vertex_positions"]),
                                          mesh.positions.ravel())
            # Mitsuba's PLY loader normalises the normals again: a float32 ulp or two.
            np.testing.assert_allclose(np.asarray(params["vertex_normals"]),
                                       mesh.normals.ravel(), rtol=0, atol=3e-7)
            np.testing.assert_array_equal(np.asarray(params["faces"]), mesh.faces.ravel())
            if key.startswith("receiver"):
                np.testing.assert_array_equal(np.asarray(params["vertex_texcoords"]),
                                              mesh.uvs.ravel())


@pytest.mark.parametrize("name", ["spot_sphere", "dispersion_sphere", "metal_ring"])
def test_loaded_xml_has_the_dicts_parameters_and_renders_the_same(tmp_path, name):
    """Every parameter Mitsuba exposes (emitter, sensor, BSDFs, meshes) equals the dict
    scene's, each shape's BSDF is the same plugin with the same settings, and the ptracer
    image from the file equals the dict's for the same seed (up to the order of its
    atomic additions)."""
    mi, _, _ = load_mitsuba()
    scene, loaded = _written(tmp_path, name)
    for channel, exported in loaded.items():
        direct = export_scene(scene, channel=channel).scene
        ours, theirs = mi.traverse(exported.scene), mi.traverse(direct)
        assert set(ours.keys()) == set(theirs.keys())
        for key in theirs.keys():
            np.testing.assert_allclose(_values(ours[key]), _values(theirs[key]), rtol=1e-6,
                                       atol=1e-6, err_msg=key)
        bsdfs = {s.id(): str(s.bsdf()) for s in direct.shapes()}
        assert {s.id(): str(s.bsdf()) for s in exported.scene.shapes()} == bsdfs
        sensor = {"type": "perspective", "fov": 40.0,
                  "to_world": mi.ScalarTransform4f().look_at(
                      origin=list(scene.camera.position), target=list(scene.camera.look_at),
                      up=list(scene.camera.up)),
                  "film": {"type": "hdrfilm", "width": 48, "height": 48}}
        sensor = mi.load_dict(sensor)
        image = np.asarray(mi.render(exported.scene, sensor=sensor, spp=4, seed=7))
        expected = np.asarray(mi.render(direct, sensor=sensor, spp=4, seed=7))
        assert expected.max() > 0
        np.testing.assert_allclose(image, expected, atol=1e-4 * expected.max())


def _maps(tracer: PhotonTracer, *, photons: int, seeds: range) -> ReceiverMap:
    """Mean and variance of the mean over independent seeds, E in W/m^2."""
    estimates = np.stack([np.asarray(s) / photons for seed in seeds
                          for s in tracer.trace(photons, seed=seed).caustic[:1]])
    extent = tracer.extents[0]
    return ReceiverMap(irradiance=estimates.mean(axis=0), extent=extent,
                       variance=estimates.var(axis=0, ddof=1) / len(seeds))


def test_photon_tracer_on_the_xml_gives_the_references_irradiance(tmp_path):
    """glass_sphere at 64 x 64 texels, 2^17 photons per seed: with the same seed the maps
    from the file and from the dict hold the same flux, texel by texel but for under 0.1 %
    of the texels (the same triangles, so the same hits; a photon grazing a texel boundary
    may land in its neighbour, as Mitsuba's PLY loader normalises the normals again,
    changing their last bit); with four independent seeds on each side, every flux ratio
    of the cross-check (total, encircled, 8 x 8 regions) is within Z_LIMIT standard
    errors of 1.
    Not vacuous: the caustic holds flux, and a map traced on half the photons' weight
    misses the total by far more than Z_LIMIT."""
    scene, loaded = _written(tmp_path, "glass_sphere")
    kwargs = {"resolution": (64, 64), "caustic_only": True}
    ours = PhotonTracer(scene, loaded=loaded, **kwargs)
    reference = PhotonTracer(scene, **kwargs)
    photons = 1 << 17
    same_ours = ours.trace(photons, seed=11).caustic[0]
    same_reference = reference.trace(photons, seed=11).caustic[0]
    assert same_reference.max() > 0
    # The same photons: the flux is the same, and only the odd photon that grazes a texel
    # boundary lands in its neighbour (the PLY's normals differ in their last bit).
    assert same_ours.sum() == pytest.approx(same_reference.sum(), rel=1e-6)
    moved = np.abs(same_ours - same_reference) > 1e-6 * same_reference.max()
    assert moved.mean() < 1e-3

    expected = _maps(reference, photons=photons, seeds=range(4))
    other = _maps(ours, photons=photons, seeds=range(4, 8))
    ratios = compare_maps(expected, other)
    z = np.array([r.z for r in ratios])
    assert len(ratios) >= 9 and np.all(np.abs(z) < Z_LIMIT), [
        (r.label, r.ratio, r.z) for r in ratios if abs(r.z) >= Z_LIMIT]
    halved = ReceiverMap(irradiance=other.irradiance / 2, extent=other.extent,
                         variance=other.variance / 4)
    total = next(r for r in compare_maps(expected, halved) if r.kind == "total")
    assert abs(total.z) > 10 * Z_LIMIT


#: A Mitsuba process that imports nothing but Mitsuba: it loads every file named on its
#: command line and renders each with the file's own sensor and integrator (8 x 8 pixels,
#: 4 samples), printing whether every pixel is finite and the largest pixel value.
_PLAIN_MITSUBA = """
import sys
import mitsuba as mi
mi.set_variant("llvm_ad_rgb")
for path in sys.argv[1:]:
    image = mi.TensorXf(mi.render(mi.load_file(path, resx=8, resy=8), spp=4)).numpy()
    print(path, bool((abs(image) < float("inf")).all()), float(image.max()))
"""


def _with_fresnel(scene):
    objects = tuple(dataclasses.replace(o, material=dataclasses.replace(o.material, fresnel=True))
                    for o in scene.objects)
    return dataclasses.replace(scene, objects=objects)


def test_stock_xml_loads_in_a_mitsuba_that_knows_nothing_of_the_harness(tmp_path):
    """Every bundled scene's stock export (``bsdf="stock"``, the default and what
    ``caustics export --format mitsuba`` writes) loads and renders in a fresh Python
    process that imports only Mitsuba (no plugin registered). Not vacuous: the
    ``harness`` file of the same scene fails to load there, naming the plugin."""
    paths = []
    for file in BUNDLED_FILES:
        paths += write_scene_xml(load_scene(file), tmp_path / bundled_id(file))
    env = {**os.environ, "DRJIT_LIBLLVM_PATH": configure_drjit()}
    done = subprocess.run([sys.executable, "-c", _PLAIN_MITSUBA, *map(str, paths)],
                          capture_output=True, text=True, env=env, cwd=tmp_path, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    rendered = {line.split(" ")[0]: line.split(" ")[1:] for line in done.stdout.splitlines()}
    assert list(rendered) == list(map(str, paths)) and len(paths) >= len(BUNDLED_FILES)
    assert all(finite == "True" and float(peak) >= 0 for finite, peak in rendered.values())
    # Lit where the camera sees a diffuse surface directly (the ptracer renders what it
    # sees only through specular surfaces black: seabed's and water_pool's floor).
    assert float(rendered[str(tmp_path / "glass_sphere" / "scene.xml")][1]) > 0
    harness = write_scene_xml(load_scene(resolve_scene("glass_sphere")), tmp_path / "h",
                              bsdf="harness")
    refused = subprocess.run([sys.executable, "-c", _PLAIN_MITSUBA, str(harness[0])],
                             capture_output=True, text=True, env=env, check=False)
    assert refused.returncode != 0 and "chain_dielectric" in refused.stderr


def test_stock_xml_is_the_reference_where_the_scene_weights_by_fresnel(tmp_path):
    """glass_sphere with ``fresnel = true``: the stock file and the ``harness`` file give
    the same ptracer image for the same seed (both reflect with probability F, weight
    one; up to the order of atomic additions), and :func:`stock_differences` names no
    difference. Without Fresnel (the bundled scene) it names the object, and the images
    differ by the Fresnel losses (the reference transmits every photon)."""
    mi, _, _ = load_mitsuba()
    scene = _with_fresnel(load_scene(resolve_scene("glass_sphere")))
    assert stock_differences(scene) == ()
    plain = load_scene(resolve_scene("glass_sphere"))
    assert [line.split(":")[0] for line in stock_differences(plain)] == [
        "objects[0].material"]

    def image(scene, bsdf, folder):
        (path,) = write_scene_xml(scene, tmp_path / folder, bsdf=bsdf)
        loaded = mi.load_file(str(path), resx=48, resy=48)
        return np.asarray(mi.render(loaded, spp=4, seed=7))

    stock = image(scene, "stock", "stock")
    exact = image(scene, "harness", "harness")
    assert exact.max() > 0
    np.testing.assert_allclose(stock, exact, atol=1e-4 * exact.max())
    no_fresnel = image(plain, "harness", "plain")
    assert np.abs(no_fresnel - stock).max() > 1e-2 * exact.max()
