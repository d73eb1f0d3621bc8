"""Bad input gets a clear exception, never a crash or a silent copy: TypeError or ValueError for arguments,
clutterseg.Error for what the core finds in files and data, with the core's one-line message."""
import json

import numpy as np
import pytest

import clutterseg
from conftest import run_cli


@pytest.fixture(scope="module")
def segmenter():
    return clutterseg.Segmenter()


@pytest.mark.parametrize("dtype", [np.int32, np.float64, np.uint8, np.int16])
def test_other_dtypes_raise_type_error(segmenter, example_frame, dtype):
    with pytest.raises(TypeError, match=r"^depth: dtype \w+ is not supported; expected uint16 or float32$"):
        segmenter.segment(example_frame.depth.astype(dtype), example_frame.camera)


def test_byte_swapped_uint16_is_not_taken_for_uint16(segmenter, example_frame):
    with pytest.raises(TypeError, match="dtype >u2 is not supported"):
        segmenter.segment(example_frame.depth.astype(">u2"), example_frame.camera)


def test_a_3d_array_raises_value_error(segmenter, example_frame):
    stacked = np.stack([example_frame.depth] * 3, axis=-1)
    with pytest.raises(ValueError, match=r"^depth: expected a 2-D array \(height x width\), got shape \(480, 640, 3\)$"):
        segmenter.segment(stacked, example_frame.camera)
    with pytest.raises(ValueError, match=r"got shape \(307200,\)"):
        segmenter.segment(example_frame.depth.ravel(), example_frame.camera)


@pytest.mark.parametrize("shape", [(0, 640), (480, 0), (0, 0)])
def test_an_empty_array_raises_value_error(segmenter, example_frame, shape):
    with pytest.raises(ValueError, match=r"^depth: the array is empty"):
        segmenter.segment(np.zeros(shape, np.uint16), example_frame.camera)


def test_non_contiguous_arrays_raise_value_error_instead_of_being_copied(segmenter, example_frame):
    depth = example_frame.depth
    every_other_column = depth[:, ::2]
    transposed = np.ascontiguousarray(depth).T
    flipped = depth[::-1]
    camera = clutterseg.Camera(525, 525, 159.5, 239.5)
    for array, cam in [(every_other_column, camera), (transposed, clutterseg.Camera(525, 525, 239.5, 319.5)),
                       (flipped, example_frame.camera)]:
        with pytest.raises(ValueError, match=r"^depth: the array is not contiguous .*numpy.ascontiguousarray"):
            segmenter.segment(array, cam)
    # Made contiguous, the same pixels are accepted.
    segmenter.segment(np.ascontiguousarray(every_other_column), camera)


def test_not_an_array_raises_type_error(segmenter, example_frame):
    with pytest.raises(TypeError, match="^depth: expected a NumPy array, got list$"):
        segmenter.segment(example_frame.depth.tolist(), example_frame.camera)
    with pytest.raises(TypeError):
        segmenter.segment(example_frame.depth, {"fx": 525, "fy": 525, "cx": 319.5, "cy": 239.5})


def test_a_camera_that_does_not_fit_raises_value_error(segmenter, example_frame):
    depth = example_frame.depth
    cases = [
        (clutterseg.Camera(262.5, 262.5, 159.5, 119.5, 320, 240), "intrinsics are for 320x240 but the image is 640x480"),
        (clutterseg.Camera(0, 525, 319.5, 239.5), "intrinsics need positive focal lengths fx, fy"),
        (clutterseg.Camera(float("nan"), 525, 319.5, 239.5), "intrinsics need positive focal lengths fx, fy"),
        (clutterseg.Camera(525, 525, 700, 239.5), r"principal point \(cx, cy\) lies outside the image"),
        (clutterseg.Camera(525, 525, 319.5, 239.5, depth_unit_m=0), "depth_unit_m must be positive"),
    ]
    for camera, message in cases:
        with pytest.raises(ValueError, match=f"^camera: {message}$"):
            segmenter.segment(depth, camera)


def test_a_frame_without_depth_raises_clutterseg_error(segmenter, example_frame):
    with pytest.raises(clutterseg.Error, match="^depth image has no valid measurement$"):
        segmenter.segment(np.zeros((480, 640), np.uint16), example_frame.camera)
    with pytest.raises(clutterseg.Error):
        segmenter.segment(np.full((480, 640), np.nan, np.float32), example_frame.camera)
    assert issubclass(clutterseg.Error, RuntimeError)
    # The stream goes on after a bad frame.
    assert segmenter.segment(example_frame.depth, example_frame.camera).object_labels.max() > 0


def test_unknown_parameters_raise_value_error_naming_them():
    for make in [lambda: clutterseg.Segmenter({"graph": {"theta_x": 1}}),
                 lambda: clutterseg.Segmenter({"graph.theta_x": 1}),
                 lambda: clutterseg.Segmenter(graph__theta_x=1),
                 lambda: clutterseg.Segmenter(graph={"theta_x": 1})]:
        with pytest.raises(ValueError, match=r"^clutterseg.Segmenter params: unknown parameter 'graph.theta_x'$"):
            make()
    with pytest.raises(ValueError, match="unknown parameter 'theta_c'"):
        clutterseg.Segmenter(theta_c=0.6)


def test_wrong_parameter_types_raise_value_error_naming_them():
    # The core's params_from_json decides; the message names the parameter it refused.
    for params, key in [({"graph": {"theta_c": "high"}}, "graph.theta_c"), ({"seed": True}, "seed"),
                        ({"curvature.theta_h": 0.4, "smoothing": {"temporal": 3.5}}, "smoothing.temporal"),
                        ({"graph": 0.5}, "graph")]:
        with pytest.raises(ValueError, match=f"^clutterseg.Segmenter params: .*'{key}'"):
            clutterseg.Segmenter(params)
    with pytest.raises(ValueError, match=r"^clutterseg.Segmenter params: parameter 'graph.theta_c' must be a number or a bool, got set$"):
        clutterseg.Segmenter(graph__theta_c={0.5})
    with pytest.raises(TypeError):
        clutterseg.Segmenter([("graph.theta_c", 0.5)])


def test_file_errors_carry_the_same_message_as_the_cli(tmp_path, example_frame):
    # The CLI prints "clutterseg: <message>" and exits non-zero; Python raises clutterseg.Error(<message>).
    camera_file = tmp_path / "camera.json"
    camera_file.write_text(json.dumps({"fx": 525, "fy": 525, "cx": 319.5}))
    cli = run_cli("segment", example_frame.path, "--camera", camera_file, "--out", tmp_path / "out", check=False)
    assert cli.returncode == 1
    with pytest.raises(clutterseg.Error) as python_error:
        clutterseg.Camera.from_json(camera_file)
    assert cli.stderr.strip() == f"clutterseg: {python_error.value}"
    assert str(python_error.value).startswith(f"{camera_file}: needs numbers fx, fy, cx, cy, width, height")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rgba = tmp_path / "rgba.png"
    plt.imsave(rgba, np.zeros((48, 64)))  # an 8-bit RGBA PNG (OpenCV reads it as colour), not a depth image
    cli = run_cli("segment", rgba, "--fx", 60, "--out", tmp_path / "out", check=False)
    assert cli.returncode == 1
    with pytest.raises(clutterseg.Error) as python_error:
        clutterseg.read_depth(rgba)
    assert cli.stderr.strip() == f"clutterseg: {python_error.value}"
    assert str(python_error.value) == f"{rgba}: is a 8-bit 3-channel image; depth must be a 16-bit single-channel PNG"
    assert "\n" not in str(python_error.value)

    with pytest.raises(clutterseg.Error, match="is not a dataset folder"):
        clutterseg.Dataset(tmp_path)
    with pytest.raises(clutterseg.Error, match="missing.png: no such file$"):
        clutterseg.read_labels(tmp_path / "missing.png")
