"""The GIL is released while a frame is segmented: Segmenters in threads run at the same time and give
exactly what one thread gives; one Segmenter shared by threads serialises its calls."""
import threading
import time

import numpy as np

import clutterseg
from conftest import DATA_DIR


def stream(frames, segmenter):
    return [segmenter.segment(f.depth, f.camera).object_labels for f in frames]


def test_two_threads_give_the_same_labels_as_one():
    frames = list(clutterseg.Dataset(DATA_DIR / "tabletop-realsense"))[:5]
    frames_b = list(clutterseg.Dataset(DATA_DIR / "osd-kinect"))
    expected_a = stream(frames, clutterseg.Segmenter())
    expected_b = stream(frames_b, clutterseg.Segmenter())

    results = {}
    barrier = threading.Barrier(2)

    def run(key, frames):
        barrier.wait()
        results[key] = stream(frames, clutterseg.Segmenter())

    threads = [threading.Thread(target=run, args=("a", frames)), threading.Thread(target=run, args=("b", frames_b))]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
        assert not t.is_alive()
    for key, expected in [("a", expected_a), ("b", expected_b)]:
        assert len(results[key]) == len(expected)
        for got, want in zip(results[key], expected):
            assert np.array_equal(got, want)


def test_python_runs_while_a_frame_is_segmented(example_frame):
    # With the GIL held through the C++ call, no other Python thread could run until the call returns.
    # Result._core_window is when the C++ call ran, on time.perf_counter()'s clock.
    segmenter = clutterseg.Segmenter(threads=1)
    windows = []

    def work():
        for _ in range(3):
            windows.append(segmenter.segment(example_frame.depth, example_frame.camera)._core_window)

    worker = threading.Thread(target=work)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
    worker.join()
    inside = sum(start < t < end for start, end in windows for t in ticks)
    assert inside > 100, f"only {inside} Python steps ran during the C++ calls"


def test_one_segmenter_shared_by_threads_takes_turns():
    frames = list(clutterseg.Dataset(DATA_DIR / "ycbv-0000"))[:4]
    # Every call independent of the order: no temporal window, no tracked ids.
    segmenter = clutterseg.Segmenter(smoothing__temporal=False, tracking__enabled=False)
    expected = stream(frames, clutterseg.Segmenter(smoothing__temporal=False, tracking__enabled=False))
    got = [[None] * len(frames) for _ in range(2)]

    def run(k):
        for i, f in enumerate(frames):
            got[k][i] = segmenter.segment(f.depth, f.camera).object_labels

    threads = [threading.Thread(target=run, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    for k in range(2):
        for g, e in zip(got[k], expected):
            assert np.array_equal(g, e)
