"""Scene keys of a scan body: accepted values, one-line errors naming the key, round trip."""

from __future__ import annotations

import tomllib

import pytest

from fenics_garment.scene import config

BASE = {"body": {"kind": "scan", "file": "body.obj"}, "garment": {"kind": "gilet"}}


def _scene(**body):
    return config.from_dict({**BASE, "body": {**BASE["body"], **body}}, "scene.toml")


def test_scan_keys_round_trip():
    s = _scene(units="dm", up="-y", max_hole_edges=80, remesh=True, landmarks={"waist": 1.05})
    again = config.from_dict(tomllib.loads(config.dumps(s)))
    assert again.body == s.body
    assert _scene(scale=0.0254).body.scale == 0.0254


@pytest.mark.parametrize(
    "body, key, words",
    [
        ({"units": "ft"}, "body.units", "mm, cm, dm, m, in"),
        ({"up": "w"}, "body.up", "x, -x"),
        ({"scale": -1.0}, "body.scale", "positive"),
        ({"scale": 0.1, "units": "dm"}, "body.scale", "not both"),
        ({"landmarks": {"wasit": 1.0}}, "body.landmarks.wasit", "waist"),
        ({"landmarks": {"waist": -1.0}}, "body.landmarks.waist", "height"),
    ],
)
def test_bad_scan_keys(body, key, words):
    with pytest.raises(config.SceneError) as err:
        _scene(**body)
    msg = str(err.value)
    assert f"[{key}]" in msg and words in msg and "\n" not in msg
