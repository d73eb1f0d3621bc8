"""The Python layer adds nothing and loses nothing: on every real dev frame, processed as a stream the
way `clutterseg segment DIR` processes a folder (one Segmenter, temporal smoothing across frames), the
label images from Python equal the PNGs the CLI writes byte for byte, and the objects equal its JSON."""
import json

import numpy as np
import pytest

import clutterseg
from conftest import DATA_DIR, DEV_SETS, run_cli


@pytest.fixture(scope="module", params=DEV_SETS)
def dev_set(request, tmp_path_factory):
    name = request.param
    out = tmp_path_factory.mktemp(name)
    run_cli("segment", DATA_DIR / name, "--out", out)
    return name, out


def test_labels_equal_the_cli_pngs_on_every_frame(dev_set):
    name, out = dev_set
    dataset = clutterseg.Dataset(DATA_DIR / name)
    segmenter = clutterseg.Segmenter()
    assert len(dataset) > 0
    for frame in dataset:
        result = segmenter.segment(frame.depth, frame.camera)
        cli_labels = clutterseg.read_labels(out / "label" / f"{frame.name}.png")
        cli_patches = clutterseg.read_labels(out / "patch" / f"{frame.name}.png")
        # Byte for byte: the uint16 images the CLI encodes, from the int32 images Python returns.
        assert result.object_labels.max() <= 65535
        assert result.object_labels.astype(np.uint16).tobytes() == cli_labels.astype(np.uint16).tobytes(), frame.name
        assert result.core_patch_labels.astype(np.uint16).tobytes() == cli_patches.astype(np.uint16).tobytes(), frame.name
        assert result.object_labels.max() > 1, f"{name}/{frame.name}: nothing segmented"

        cli = json.loads((out / f"{frame.name}.json").read_text())
        assert [o.id for o in result.objects] == [o["id"] for o in cli["objects"]]
        for ours, theirs in zip(result.objects, cli["objects"]):
            assert ours.pixel_count == theirs["pixels"]
            assert ours.patches == theirs["patches"]
            assert (ours.support, ours.background) == (theirs["support"], theirs["background"])
            assert np.array_equal(ours.centroid, np.float32(theirs["centroid"]))
            assert np.array_equal(ours.box.extents, np.float32(theirs["box"]["extents"]))
            if theirs["cut_cost"] is None:
                assert ours.cut_cost == float("inf")
            else:
                assert np.float32(ours.cut_cost) == np.float32(theirs["cut_cost"])
        assert len(result.patches) == len(cli["patches"])
        assert [(e.a, e.b, e.cue) for e in result.graph] == [(e["a"], e["b"], e["cue"]) for e in cli["graph"]]
        if cli["support_plane"] is None:
            assert result.support_plane is None
        else:
            assert np.array_equal(result.support_plane.normal, np.float32(cli["support_plane"]["normal"]))
        assert set(result.timings_ms) == set(cli["timings_ms"])  # the same stages (JSON sorts them)


def test_objects_only_labels_equal_the_cli_with_objects_only(tmp_path):
    dataset = clutterseg.Dataset(DATA_DIR / "ycbv-0003")
    run_cli("segment", dataset.path, "--out", tmp_path, "--objects-only", "--no-temporal")
    segmenter = clutterseg.Segmenter({"support": {"objects_only": True}, "smoothing.temporal": False})
    for frame in dataset:
        result = segmenter.segment(frame.depth, frame.camera)
        cli_labels = clutterseg.read_labels(tmp_path / "label" / f"{frame.name}.png")
        assert np.array_equal(result.objects_only_labels, cli_labels)
        kept = [o for o in result.objects if not (o.support or o.background)]
        # Tracked ids (on by default) are kept in the objects-only view: the ids of the kept objects.
        assert set(np.unique(result.objects_only_labels)) - {0} == {o.id for o in kept}
        assert not np.array_equal(result.objects_only_labels, result.object_labels)
