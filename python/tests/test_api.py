"""What a Python user relies on: parameters by dict or keyword with the CLI's names, temporal state kept
in the Segmenter, results that describe every object, and help() that says what arguments mean."""
import ast
import json
import pydoc
from pathlib import Path

import numpy as np
import pytest

import clutterseg
from conftest import DATA_DIR, run_cli


def test_params_are_the_dump_config_and_round_trip():
    dumped = json.loads(run_cli("--dump-config").stdout)
    assert clutterseg.default_params() == dumped
    custom = clutterseg.Segmenter({"graph": {"theta_c": 0.7}, "curvature.theta_h": 0.4}, seed=9,
                                  support__objects_only=True, smoothing={"temporal_frames": 3})
    expected = json.loads(json.dumps(dumped))
    expected["graph"]["theta_c"] = 0.7
    expected["curvature"]["theta_h"] = 0.4
    expected["seed"] = 9
    expected["support"]["objects_only"] = True
    expected["smoothing"]["temporal_frames"] = 3
    assert custom.params == expected
    # The dict form of .params is accepted back, and keywords win over the dict.
    assert clutterseg.Segmenter(custom.params).params == expected
    assert clutterseg.Segmenter(custom.params, graph__theta_c=0.3).params["graph"]["theta_c"] == 0.3
    assert clutterseg.Segmenter({"graph.theta_c": np.float32(0.25)}).params["graph"]["theta_c"] == 0.25


def test_parameters_change_the_segmentation(example_frame):
    # Theta_c = 2 cuts every link (weights are at most 1): each patch becomes an object of its own.
    split = clutterseg.segment(example_frame.depth, example_frame.camera, graph__theta_c=2)
    default = clutterseg.segment(example_frame.depth, example_frame.camera)
    assert len(split.objects) > len(default.objects)
    assert all(o.cut_cost == float("inf") for o in split.objects)


def test_the_segmenter_keeps_the_temporal_window_and_reset_forgets_it():
    frames = list(clutterseg.Dataset(DATA_DIR / "ycbv-0000"))[:3]
    stream = clutterseg.Segmenter()
    for f in frames[:2]:
        stream.segment(f.depth, f.camera)
    smoothed = stream.segment(frames[2].depth, frames[2].camera)
    alone = clutterseg.Segmenter().segment(frames[2].depth, frames[2].camera)
    assert not np.array_equal(smoothed.depth, alone.depth)  # the window averaged earlier frames in
    stream.reset()
    again = stream.segment(frames[2].depth, frames[2].camera)
    assert np.array_equal(again.depth, alone.depth) and np.array_equal(again.object_labels, alone.object_labels)
    # clutterseg.segment is one frame without a window.
    one = clutterseg.segment(frames[2].depth, frames[2].camera)
    assert np.array_equal(one.object_labels, clutterseg.Segmenter(smoothing__temporal=False)
                          .segment(frames[2].depth, frames[2].camera).object_labels)


def test_float_metres_give_the_same_labels_as_millimetres(example_frame):
    millimetres = clutterseg.segment(example_frame.depth, example_frame.camera)
    metres = example_frame.depth.astype(np.float32) * np.float32(example_frame.camera.depth_unit_m)
    metres[example_frame.depth == 0] = np.nan  # NaN is "no measurement" in float input
    assert np.array_equal(clutterseg.segment(metres, example_frame.camera).object_labels, millimetres.object_labels)


def test_a_camera_without_size_takes_the_images(example_frame):
    c = example_frame.camera
    bare = clutterseg.Camera(c.fx, c.fy, c.cx, c.cy)
    assert (bare.width, bare.height) == (0, 0)
    assert np.array_equal(clutterseg.segment(example_frame.depth, bare).object_labels,
                          clutterseg.segment(example_frame.depth, c).object_labels)


def test_camera_json_round_trip(tmp_path):
    camera = clutterseg.Camera(612.9, 613.1, 322.5, 248.1, 640, 480, depth_unit_m=0.0001)
    camera.to_json(tmp_path / "camera.json")
    back = clutterseg.Camera.from_json(tmp_path / "camera.json")
    assert repr(back) == repr(camera)
    assert np.array_equal(back.camera_to_robot, np.eye(4))


def test_objects_describe_themselves(example_frame):
    result = clutterseg.segment(example_frame.depth, example_frame.camera)
    fields = ["id", "pixel_count", "centroid", "box", "patches", "cut_cost", "support", "background"]
    for i, obj in enumerate(result.objects):
        d = obj.as_dict()
        assert list(d)[:len(fields)] == fields
        assert obj.id == i + 1
        assert obj.pixel_count == np.count_nonzero(result.object_labels == obj.id)
        assert set(obj.patches) <= set(np.unique(result.patch_labels[result.object_labels == obj.id]))
        assert sorted(d["box"]) == ["axes", "center", "extents"]
        assert np.allclose(np.linalg.norm(obj.box.axes, axis=0), 1, atol=1e-5)
        assert obj.confidence == obj.cut_cost
    assert sum(o.support for o in result.objects) == 1
    assert result.support_plane is not None
    assert abs(np.linalg.norm(result.support_plane.normal) - 1) < 1e-5
    assert list(result.timings_ms)[-1] == "total"
    assert {e.cue for e in result.graph} <= {"adjacent", "coplanar", "curvature-open", "curvature-occluded"}
    assert result.patches[0].histogram.shape == (11, 11)
    assert result.patches[0].histogram.sum() == pytest.approx(1, abs=1e-5)
    assert len(result.patches[0].pixels) == result.patches[0].pixel_count
    assert result.objects is result.objects  # built once


def test_help_says_what_each_argument_is_with_units():
    segmenter_help = pydoc.render_doc(clutterseg.Segmenter, renderer=pydoc.plaintext)
    for words in ["graph__theta_c", "dotted keys", "uint16 in steps of camera.depth_unit_m", "float32 in metres",
                  "ValueError", "GIL"]:
        assert words in segmenter_help, words
    camera_help = pydoc.render_doc(clutterseg.Camera, renderer=pydoc.plaintext)
    for words in ["focal lengths [px]", "principal point [px]", "metres per step"]:
        assert words in camera_help, words
    result_help = pydoc.render_doc(clutterseg.Result, renderer=pydoc.plaintext)
    for words in ["object_labels", "float32 (H, W, 3): camera-frame points [m]", "timings_ms"]:
        assert words in result_help, words


def test_dataset_frames(example_frame):
    dataset = clutterseg.Dataset(DATA_DIR / "ycbv-0000")
    assert len(dataset) == 10 and dataset.names[0] == "000001"
    frame = dataset["000003"]
    assert frame.depth.dtype == np.uint16 and frame.label.dtype == np.int32 and frame.color.shape == (480, 640, 3)
    assert frame.camera.fx == pytest.approx(1066.778)
    assert np.array_equal(frame.label, clutterseg.read_labels(DATA_DIR / "ycbv-0000" / "label" / "000003.png"))
    assert example_frame.label is None
    with pytest.raises(KeyError):
        dataset["nope"]


def stub_names(path):
    """Top-level names of a .pyi file, and the members of each class as "Class.member"."""
    names = set()
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        if isinstance(node, ast.ClassDef):
            names |= {f"{node.name}.{n.name}" for n in node.body if isinstance(n, ast.FunctionDef)}
            names |= {f"{node.name}.{n.target.id}" for n in node.body if isinstance(n, ast.AnnAssign)}
        if isinstance(node, ast.AnnAssign):
            names.add(node.target.id)
    return names


def module_names(module):
    names = set()
    for name, value in vars(module).items():
        if name.startswith("__") or isinstance(value, type(module)):
            continue
        names.add(name)
        if isinstance(value, type) and not issubclass(value, Exception):
            names |= {f"{name}.{m}" for m in vars(value) if not m.startswith("__")}
    return names


def test_the_type_stubs_name_everything_the_module_has():
    package = Path(clutterseg.__file__).parent
    assert stub_names(package / "_clutterseg.pyi") >= module_names(clutterseg._clutterseg)
    assert stub_names(package / "synth.pyi") >= module_names(clutterseg.synth)
    assert (package / "py.typed").exists()
    import clutterseg.synth as synth_module
    assert synth_module is clutterseg.synth
