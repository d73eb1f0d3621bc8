"""clutterseg.synth is `clutterseg synth`: the same presets, the same frames, the same bytes."""
import filecmp

import numpy as np
import pytest

import clutterseg
from conftest import run_cli


def test_presets_and_sensors_are_the_clis():
    listed = run_cli("synth", "--list").stdout.split("\n")
    names = [line.split()[0] for line in listed if line.strip()]
    assert [p["name"] for p in clutterseg.synth.presets()] == names
    assert sorted(clutterseg.synth.sensors()) == ["ideal", "kinect-v1", "realsense-d435"]


def test_write_dataset_writes_the_clis_bytes(tmp_path):
    run_cli("synth", "--preset", "occluded", "--frames", "2", "--seed", "7", "--size", "160x120",
            "--sensor", "realsense-d435", "--out", tmp_path / "cli")
    clutterseg.synth.write_dataset(tmp_path / "py", "occluded", frames=2, seed=7, sensor="realsense-d435",
                                   camera=clutterseg.synth.default_camera(160, 120))
    files = sorted(p.relative_to(tmp_path / "cli") for p in (tmp_path / "cli").rglob("*") if p.is_file())
    assert len(files) == 8  # camera.json, scenes.json, 2 x depth, label, color
    match, mismatch, errors = filecmp.cmpfiles(tmp_path / "cli", tmp_path / "py", [str(f) for f in files], shallow=False)
    assert mismatch == [] and errors == []


def test_synthesize_gives_the_frames_the_cli_writes(tmp_path):
    run_cli("synth", "--preset", "cup", "--frames", "2", "--seed", "3", "--size", "320x240", "--out", tmp_path)
    camera = clutterseg.synth.default_camera(320, 240)
    frame = clutterseg.synth.synthesize("cup", seed=3, frame=1, camera=camera)
    assert np.array_equal(frame.depth_mm, clutterseg.read_depth(tmp_path / "depth" / "000001.png"))
    assert np.array_equal(frame.labels, clutterseg.read_labels(tmp_path / "label" / "000001.png"))
    assert np.array_equal(frame.color, clutterseg.read_color(tmp_path / "color" / "000001.png"))
    assert frame.family == "cup" and [o["type"] for o in frame.objects] == ["cup"]
    assert frame.objects[0]["pose"].shape == (4, 4)
    # A Segmenter finds the cup on the synthetic frame.
    result = clutterseg.Segmenter().segment(frame.depth_mm, frame.camera)
    assert clutterseg.score_frame(frame.labels, result.objects_only_labels).overlap_f > 0.5


def test_bad_names_raise_value_error():
    with pytest.raises(ValueError, match=r"^--preset nope: unknown preset \(.*boxes.*\)$"):
        clutterseg.synth.synthesize("nope")
    with pytest.raises(ValueError, match="kinect-v3"):
        clutterseg.synth.synthesize("cup", sensor="kinect-v3")
