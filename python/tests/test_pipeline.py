"""clutterseg.Pipeline: frames of one stream on several cores; Results in push order and the same as
Segmenter's for the same stream (labels, tracked ids), bad frames raised in their turn."""
import gc

import numpy as np
import pytest

import clutterseg
from conftest import DATA_DIR


@pytest.fixture(scope="module")
def stream():
    return list(clutterseg.Dataset(DATA_DIR / "ycbv-0000"))


def segmenter_results(frames, **params):
    segmenter = clutterseg.Segmenter(**params)
    out = []
    for depth, camera in frames:
        try:
            r = segmenter.segment(depth, camera)
            out.append((r.object_labels.copy(), [o.id for o in r.objects]))
        except clutterseg.Error:
            out.append(None)
    return out


def pipeline_results(frames, **params):
    pipeline = clutterseg.Pipeline(**params)
    out = []
    for depth, camera in frames:
        if pipeline.in_flight >= pipeline.capacity:
            out.append(pop(pipeline))
        pipeline.push(depth, camera)
    while pipeline.in_flight:
        out.append(pop(pipeline))
    return out


def pop(pipeline):
    try:
        r = pipeline.pop()
        return (r.object_labels.copy(), [o.id for o in r.objects])
    except clutterseg.Error:
        return None


@pytest.mark.parametrize("threads", [0, 1, 2])
def test_same_labels_and_ids_as_a_segmenter(stream, threads):
    frames = [(f.depth, f.camera) for f in stream]
    want = segmenter_results(frames)
    got = pipeline_results(frames, threads=threads)
    assert len(got) == len(want)
    for g, w in zip(got, want):
        assert np.array_equal(g[0], w[0])
        assert g[1] == w[1]


def test_a_frame_without_depth_is_raised_in_its_turn_and_the_stream_goes_on(stream):
    frames = [(f.depth, f.camera) for f in stream[:6]]
    frames.insert(3, (np.zeros_like(stream[0].depth), stream[0].camera))
    want = segmenter_results(frames)
    got = pipeline_results(frames, threads=2)
    assert [g is None for g in got] == [False, False, False, True, False, False, False]
    assert want[3] is None
    for g, w in zip(got, want):
        if w is not None:
            assert np.array_equal(g[0], w[0]) and g[1] == w[1]


def test_depth_is_read_in_place_and_kept_alive_until_popped(stream):
    pipeline = clutterseg.Pipeline(threads=1)
    depth = stream[0].depth.copy()
    address = depth.ctypes.data
    pipeline.push(depth, stream[0].camera)
    del depth
    gc.collect()
    r = pipeline.pop()
    assert r._input_address == address
    want = clutterseg.Segmenter().segment(stream[0].depth, stream[0].camera)
    assert np.array_equal(r.object_labels, want.object_labels)


def test_map_yields_every_frame_in_order_and_pop_without_a_frame_is_an_error(stream):
    pipeline = clutterseg.Pipeline()
    results = list(pipeline.map((f.depth, f.camera) for f in stream))
    want = segmenter_results([(f.depth, f.camera) for f in stream])
    assert [r.object_labels.tolist() for r in results] == [w[0].tolist() for w in want]
    assert pipeline.in_flight == 0
    with pytest.raises(ValueError, match="no frame in flight"):
        pipeline.pop()
    with pytest.raises(ValueError, match="threads"):
        clutterseg.Pipeline(threads=-5)


def test_a_pipeline_dropped_with_frames_in_flight_finishes_them_first(stream):
    # The workers read the arrays in place: the Pipeline must not let them go before the frames are done.
    for _ in range(3):
        pipeline = clutterseg.Pipeline(threads=2)
        for f in stream[:4]:
            pipeline.push(f.depth.copy(), f.camera)
        del pipeline
        gc.collect()
    pipeline = clutterseg.Pipeline(threads=2)
    pipeline.push(stream[0].depth, stream[0].camera)
    assert pipeline.pop().object_labels.shape == stream[0].depth.shape
