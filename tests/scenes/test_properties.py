"""Property-based: whatever the input, the loader returns a Scene or raises the typed
SceneError, never another exception."""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from scenes import SceneError, load_scene, parse_scene
from scenes.model import Scene
from scenes.schema import build
from tests.conftest import MINIMAL_SCENE, all_scene_files

SETTINGS = settings(max_examples=300, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])

# TOML-like values: everything tomllib can produce (plus nan/inf floats).
toml_scalars = st.one_of(
    st.booleans(), st.integers(-(2**63), 2**63 - 1),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=12),
)
toml_values = st.recursive(
    toml_scalars,
    lambda children: st.one_of(
        st.lists(children, max_size=4),
        st.dictionaries(st.text(max_size=8), children, max_size=4),
    ),
    max_leaves=12,
)

BASE_TABLES = [tomllib.loads(MINIMAL_SCENE)] + [
    tomllib.loads(p.read_text(encoding="utf-8")) for p in all_scene_files()[:4]
]


def _paths(node, prefix=()):
    """Every (path) to a value inside nested dicts and lists."""
    yield prefix
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, (*prefix, i))


def _set(root, path, value):
    node = root
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value


def _delete(root, path):
    node = root
    for key in path[:-1]:
        node = node[key]
    del node[path[-1]]


def _check(table) -> None:
    try:
        result = build(Scene, table, file="fuzz.toml", base_dir=Path.cwd())
    except SceneError as error:
        assert error.problems, "SceneError without problems"
        for problem in error.problems:
            assert str(problem).startswith("fuzz.toml")
    else:
        assert isinstance(result, Scene)


@SETTINGS
@given(st.text(max_size=400))
def test_arbitrary_text_gives_only_scene_errors(text):
    """Random text: a Scene or a SceneError naming the file, nothing else."""
    try:
        parse_scene(text, file="fuzz.toml")
    except SceneError as error:
        assert all(str(p).startswith("fuzz.toml") for p in error.problems)


@SETTINGS
@given(st.data())
def test_replacing_any_value_gives_only_scene_errors(data):
    """Replace one value anywhere in a valid scene with any TOML value."""
    table = copy.deepcopy(data.draw(st.sampled_from(BASE_TABLES)))
    paths = [p for p in _paths(table) if p]
    path = data.draw(st.sampled_from(paths))
    _set(table, path, data.draw(toml_values))
    _check(table)


@SETTINGS
@given(st.data())
def test_deleting_or_adding_keys_gives_only_scene_errors(data):
    """Delete one key or add an unknown one anywhere."""
    table = copy.deepcopy(data.draw(st.sampled_from(BASE_TABLES)))
    paths = [p for p in _paths(table) if p]
    path = data.draw(st.sampled_from(paths))
    if data.draw(st.booleans()):
        _delete(table, path)
    else:
        dicts = [p for p in _paths(table) if isinstance(_get(table, p), dict)]
        target = _get(table, data.draw(st.sampled_from(dicts)))
        target[data.draw(st.text(min_size=1, max_size=8))] = data.draw(toml_values)
    _check(table)


def _get(root, path):
    node = root
    for key in path:
        node = node[key]
    return node


@SETTINGS
@given(st.binary(max_size=300))
def test_arbitrary_bytes_in_a_file_give_only_scene_errors(tmp_path_factory, raw):
    path = tmp_path_factory.mktemp("fuzz") / "scene.toml"
    path.write_bytes(raw)
    try:
        load_scene(path)
    except SceneError as error:
        assert all(str(p).startswith(str(path)) for p in error.problems)
