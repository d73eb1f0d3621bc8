"""No copies across the boundary: the core reads the caller's depth array in place, and result images
are NumPy arrays on the core's own buffers."""
import gc

import numpy as np

import clutterseg


def cropped_camera(camera, x0, y0, width, height):
    return clutterseg.Camera(camera.fx, camera.fy, camera.cx - x0, camera.cy - y0, width, height, camera.depth_unit_m)


def test_the_core_reads_the_depth_array_in_place(example_frame):
    depth = example_frame.depth
    assert depth.flags.c_contiguous and depth.dtype == np.uint16
    result = clutterseg.Segmenter().segment(depth, example_frame.camera)
    assert result._input_address == depth.ctypes.data

    metres = depth.astype(np.float32) * np.float32(0.001)
    result = clutterseg.Segmenter().segment(metres, example_frame.camera)
    assert result._input_address == metres.ctypes.data


def test_a_cropped_view_is_read_in_place_with_its_row_stride(example_frame):
    # A window of a larger array: rows are padded, pixels within a row adjacent; no copy either.
    x0, y0, width, height = 100, 60, 400, 300
    window = example_frame.depth[y0:y0 + height, x0:x0 + width]
    assert not window.flags.c_contiguous
    camera = cropped_camera(example_frame.camera, x0, y0, width, height)
    result = clutterseg.Segmenter().segment(window, camera)
    assert result._input_address == window.ctypes.data
    assert result.object_labels.shape == (height, width)
    # The same pixels as a compact copy give the same segmentation.
    compact = clutterseg.Segmenter().segment(np.ascontiguousarray(window), camera)
    assert np.array_equal(result.object_labels, compact.object_labels)


def test_result_images_are_views_on_the_core_buffers(example_frame):
    result = clutterseg.Segmenter().segment(example_frame.depth, example_frame.camera)
    for name in ["object_labels", "patch_labels", "core_patch_labels", "depth", "points", "edge_value", "edges"]:
        first, second = getattr(result, name), getattr(result, name)
        assert type(first.base).__name__ == "PyCapsule", name  # owned by the cv::Mat, not a NumPy copy
        assert np.shares_memory(first, second), f"{name} is copied on every access"
    for plane in result.normal_planes:
        assert type(plane.base).__name__ == "PyCapsule"
    # The interleaved normals are the one copy; the planes hold the same numbers.
    assert np.array_equal(result.normals, np.stack(result.normal_planes, axis=-1))
    assert result.points.shape == (480, 640, 3) and result.points.dtype == np.float32
    assert result.object_labels.dtype == np.int32


def test_result_images_outlive_the_result(example_frame):
    result = clutterseg.Segmenter().segment(example_frame.depth, example_frame.camera)
    labels, points = result.object_labels, result.points
    expected_labels, expected_points = labels.copy(), points.copy()
    del result
    gc.collect()
    for _ in range(3):  # new frames reuse freed memory: a dangling view would now see other numbers
        clutterseg.Segmenter().segment(example_frame.depth[::-1].copy(), example_frame.camera)
    assert np.array_equal(labels, expected_labels)
    assert np.array_equal(points, expected_points)
