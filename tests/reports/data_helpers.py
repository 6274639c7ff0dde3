"""Reading back the float data a linked scene page ships (``reports.page_data``):
each view's ``data_<view>.js`` and the shared blobs under ``_data`` beside the scene
folders, decoded with the module's own :func:`~reports.page_data.unpack`, the method
composed as the page composes it."""

from __future__ import annotations

import base64
import json
import re
from pathlib import Path

import numpy as np

from reports.page_data import BLOB_FOLDER, unpack


def view_meta(script: str) -> dict:
    """The object a ``data_<view>.js`` script assigns."""
    return json.loads(re.search(r"\] = (\{.*\});\s*$", script, re.S).group(1))


def blob_payload(script: str) -> tuple[str, bytes]:
    """Key and packed bytes of a blob script."""
    key, text = re.search(r'causticsBlobs\["(\w+)"\] = "([^"]*)";', script).groups()
    return key, base64.b64decode(text)


def page_layers(scene_dir: Path, view: str) -> tuple[dict, dict[str, np.ndarray]]:
    """A view's meta and its layers as the page reads them: ``method`` composed as
    ``fround(reference + difference)`` where ``method_exceptions`` is NaN, 1-channel
    layers as (H, W)."""
    meta = view_meta((scene_dir / f"data_{view}.js").read_text("utf-8"))
    h, w = meta["height"], meta["width"]
    layers = {}
    for name, layer in meta["layers"].items():
        script = (scene_dir.parent / BLOB_FOLDER / f"{layer['blob']}.js").read_text("ascii")
        key, payload = blob_payload(script)
        assert key == layer["blob"]
        values = unpack(payload, (h, w, layer["channels"]))
        layers[name] = values[..., 0] if layer["channels"] == 1 else values
    composed = (layers["reference"].astype(np.float64) + layers["difference"]).astype(np.float32)
    exceptions = layers.pop("method_exceptions")
    layers["method"] = np.where(np.isnan(exceptions), composed, exceptions)
    return meta, layers
