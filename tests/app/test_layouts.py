"""Layout files: the shipped presets load, bad files are refused with the key, saving round-trips."""

import json

import pytest

from app.layouts import LAYOUT_DIR, Layout, layout_path, list_layouts, load_layout, save_layout
from evpose.errors import InputError


def test_shipped_layouts_load():
    found = list_layouts(LAYOUT_DIR)
    for name in ("debug", "teaching", "compare"):
        assert isinstance(found[name], Layout), found.get(name)
    assert found["teaching"].panels["teaching"].visible
    assert found["teaching"].scene.follow


def test_bad_layout_files_name_the_problem(tmp_path):
    cases = {
        "syntax": ("{", "not valid JSON"),
        "panel": (json.dumps({"name": "x", "panels": {"bogus": {}}}), "panels.bogus"),
        "dock": (json.dumps({"name": "x", "panels": {"plots": {"dock": "upside"}}}), "dock"),
        "scene": (json.dumps({"name": "x", "scene": {"lasers": True}}), "scene"),
    }
    for stem, (text, needle) in cases.items():
        (tmp_path / f"{stem}.json").write_text(text)
        with pytest.raises(InputError, match=needle):
            load_layout(tmp_path / f"{stem}.json")
    listed = list_layouts(tmp_path)
    assert all(isinstance(v, str) for v in listed.values())


def test_saved_layout_round_trips(tmp_path):
    lay = load_layout(LAYOUT_DIR / "compare.json")
    lay.name = "mine"
    lay.scene.raw_cloud = True
    path = save_layout(lay, tmp_path)
    again = load_layout(path)
    assert again.to_dict() == lay.to_dict()


def test_layout_names_cannot_escape_the_folder(tmp_path):
    for bad in ("../evil", "a/b", "", "x" * 65):
        with pytest.raises(InputError):
            layout_path(bad, tmp_path)
