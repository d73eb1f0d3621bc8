"""Tracking through Python: object ids stay with the objects of a stream, the tracking fields are there, and
tracking.enabled = False numbers objects 1..M every frame (docs/TRACKING.md)."""
import numpy as np

import clutterseg
from conftest import DATA_DIR


def test_a_static_scene_keeps_its_ids_and_reports_age():
    frame = clutterseg.Dataset(DATA_DIR / "ycbv-0003")[0]
    segmenter = clutterseg.Segmenter()
    first = segmenter.segment(frame.depth, frame.camera)
    for k in range(2, 5):  # the same frame again: every object is the same object
        again = segmenter.segment(frame.depth, frame.camera)
    assert [o.id for o in first.objects] == sorted(o.id for o in first.objects)
    big = {o.id for o in first.objects if o.pixel_count > 2000}
    assert big and big <= {o.id for o in again.objects}
    for o in again.objects:
        if o.id in big:
            assert o.age == 4 and o.frames_missed == 0 and o.split_from == 0
            assert np.count_nonzero(again.object_labels == o.id) == o.pixel_count
    d = again.objects[0].as_dict()
    assert {"age", "frames_missed", "split_from", "merged_with"} <= set(d)
    assert isinstance(again.hidden_objects, list)


def test_without_tracking_ids_are_one_to_m_every_frame():
    dataset = clutterseg.Dataset(DATA_DIR / "ycbv-0000")
    segmenter = clutterseg.Segmenter(tracking__enabled=False)
    for frame in list(dataset)[:3]:
        result = segmenter.segment(frame.depth, frame.camera)
        assert [o.id for o in result.objects] == list(range(1, len(result.objects) + 1))
        assert all(o.age == 1 for o in result.objects)
        assert result.hidden_objects == []


def test_reset_starts_ids_again():
    frame = clutterseg.Dataset(DATA_DIR / "ycbv-0003")[0]
    segmenter = clutterseg.Segmenter()
    a = segmenter.segment(frame.depth, frame.camera)
    segmenter.reset()
    b = segmenter.segment(frame.depth, frame.camera)
    assert np.array_equal(a.object_labels, b.object_labels)
