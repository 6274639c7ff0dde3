"""`caustics export`: the files each format writes, the tolerance option, and errors as
one line with exit 1 (a tolerance no shape meets) or 2 (usage)."""

from __future__ import annotations

import json

import pygltflib as gl
import pytest

from harness.cli import main


def test_gltf_binary_and_separate(tmp_path, capsys):
    """The default writes DIR/<scene>.glb; --gltf-container gltf a .gltf and its .bin;
    --tolerance reaches the asset and refines the ring (703 segments at 1e-5 m)."""
    assert main(["export", "metal_ring", "-o", str(tmp_path / "a"), "--tolerance", "1e-5"]) == 0
    line = capsys.readouterr().err
    assert "metal_ring.glb" in line and "segments 703" in line
    read = gl.GLTF2().load(str(tmp_path / "a" / "metal_ring.glb"))
    assert read.asset.extras["harness"]["tessellation"]["tolerance_m"] == 1e-5
    assert main(["export", "glass_sphere", "-o", str(tmp_path / "b"),
                 "--gltf-container", "gltf"]) == 0
    document = json.loads((tmp_path / "b" / "glass_sphere.gltf").read_text())
    assert document["buffers"][0]["uri"] == "glass_sphere.bin"
    assert (tmp_path / "b" / "glass_sphere.bin").stat().st_size == \
        document["buffers"][0]["byteLength"]


def test_mitsuba_writes_xml_and_meshes(tmp_path, capsys):
    assert main(["export", "dispersion_sphere", "--format", "mitsuba", "-o",
                 str(tmp_path)]) == 0
    assert sorted(p.name for p in tmp_path.glob("*.xml")) == ["scene_b.xml", "scene_g.xml",
                                                             "scene_r.xml"]
    assert sorted(p.name for p in (tmp_path / "meshes").iterdir()) == ["object_0.ply",
                                                                      "receiver_0.ply"]
    text = (tmp_path / "scene_r.xml").read_text()
    assert 'type="dielectric"' in text and "chain_dielectric" not in text
    err = capsys.readouterr().err
    assert "scene_r.xml" in err
    # The stock BSDF's one difference from the reference here: it weights by Fresnel.
    assert [line for line in err.splitlines() if line.startswith("note:")] == [
        "note: dispersion_sphere: objects[0].material: the scene transmits every photon "
        "(fresnel = false); Mitsuba's dielectric weights by Fresnel"]
    assert main(["export", "dispersion_sphere", "--format", "mitsuba", "--mitsuba-bsdf",
                 "harness", "-o", str(tmp_path / "h")]) == 0
    assert "chain_dielectric" in (tmp_path / "h" / "scene_r.xml").read_text()
    assert "note:" not in capsys.readouterr().err


def test_errors_are_one_line(tmp_path, capsys):
    """A tolerance no icosphere meets: exit 1 naming the file and field; --tolerance with
    --format mitsuba, --mitsuba-bsdf with glTF, or a tolerance not a positive number:
    exit 2."""
    assert main(["export", "glass_sphere", "-o", str(tmp_path), "--tolerance", "1e-9"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "glass_sphere.toml: objects[0].subdivisions" in err
    assert main(["export", "glass_sphere", "-o", str(tmp_path), "--format", "mitsuba",
                 "--tolerance", "1e-3"]) == 2
    assert "--tolerance applies to --format gltf" in capsys.readouterr().err
    assert main(["export", "glass_sphere", "-o", str(tmp_path), "--mitsuba-bsdf",
                 "harness"]) == 2
    assert "--mitsuba-bsdf applies to --format mitsuba" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_:
        main(["export", "glass_sphere", "-o", str(tmp_path), "--tolerance", "0"])
    assert exit_.value.code == 2
    assert "positive number of metres" in capsys.readouterr().err
