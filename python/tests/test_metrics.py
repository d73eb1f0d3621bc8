"""The scorer from Python is `clutterseg eval`'s: per-frame scores equal its scenes.csv, the summary
equals its summary.json, for clutterseg on real frames and for another method's predictions (--pred)."""
import csv
import json
import math

import numpy as np
import pytest

import clutterseg
from conftest import DATA_DIR, run_cli


def eval_outputs(out):
    rows = list(csv.DictReader((out / "scenes.csv").open()))
    summary = json.loads((out / "summary.json").read_text())
    return rows, summary


def assert_frames_match(evaluation, rows):
    assert [r["frame"] for r in rows] == [f.frame for f in evaluation.frames]
    for record, row in zip(evaluation.frames, rows):
        assert (record.family, record.scene, record.error) == (row["family"], row["scene"], row["error"])
        assert not record.failed
        assert record.scores.gt_objects == int(row["gt_objects"])
        assert record.scores.pred_objects == int(row["pred_objects"])
        assert record.scores.matched == int(row["matched"])
        for name in clutterseg.SCORE_NAMES:
            value = getattr(record.scores, name)
            if row[name] == "":
                assert math.isnan(value), (record.frame, name)
            else:
                assert value == pytest.approx(float(row[name]), abs=6e-7), (record.frame, name)  # CSV: %.6f


def assert_groups_match(groups, expected):
    assert [g["family"] for g in groups] == [g["family"] for g in expected]
    for ours, theirs in zip(groups, expected):
        for key in ["frames", "scenes", "failed", "unscored"]:
            assert ours[key] == theirs[key], (ours["family"], key)
        for name in clutterseg.SCORE_NAMES:
            a, b = ours["scores"][name], theirs["scores"][name]
            assert a["scenes"] == b["scenes"]
            for field in ["mean", "std"]:
                if b[field] is None:
                    assert a[field] is None, (ours["family"], name, field)
                else:
                    assert a[field] == pytest.approx(b[field], rel=1e-12, abs=1e-15), (ours["family"], name, field)


def test_clutterseg_scores_equal_eval_on_a_real_sequence(tmp_path):
    dataset = DATA_DIR / "ycbv-0000"
    run_cli("eval", dataset, "--sequence", "--report-frames", "0", "--out", tmp_path)
    rows, summary = eval_outputs(tmp_path)
    rows = [r for r in rows if r["method"] == "clutterseg"]

    segmenter = clutterseg.Segmenter(support__objects_only=True)  # what eval runs
    evaluation = clutterseg.evaluate(dataset, lambda f: segmenter.segment(f.depth, f.camera).objects_only_labels,
                                     reset=segmenter.reset, sequence=True)
    assert len(evaluation.frames) == 10
    assert_frames_match(evaluation, rows)
    assert_groups_match(evaluation.groups, summary["runs"][0]["groups"])
    assert 0 < evaluation.mean("overlap_f") < 1


def merge_first_two(labels):
    """A deliberately imperfect method: the ground truth with objects 1 and 2 merged and ids shifted."""
    pred = labels.copy()
    pred[pred == 2] = 1
    pred[pred > 0] += 10
    return pred


def test_another_methods_predictions_score_as_eval_pred_scores_them(tmp_path):
    data = tmp_path / "synth"
    clutterseg.synth.write_dataset(data, "mixed", frames=4, seed=5, camera=clutterseg.synth.default_camera(160, 120))
    dataset = clutterseg.Dataset(data)
    pred_dir = tmp_path / "pred"
    for frame in dataset:
        clutterseg.write_labels(pred_dir / f"{frame.name}.png", merge_first_two(frame.label))
    run_cli("eval", data, "--pred", pred_dir, "--report-frames", "0", "--out", tmp_path / "eval")
    rows, summary = eval_outputs(tmp_path / "eval")

    evaluation = clutterseg.evaluate(dataset, lambda f: merge_first_two(f.label))
    assert_frames_match(evaluation, rows)
    assert_groups_match(evaluation.groups, summary["runs"][0]["groups"])
    assert [g["family"] for g in evaluation.groups] == ["all", "mixed"]
    assert evaluation.mean("overlap_f") < 1  # the merge costs something


def test_ground_truth_against_itself_scores_perfectly():
    frame = clutterseg.synth.synthesize("boxes", seed=2, camera=clutterseg.synth.default_camera(160, 120))
    truth = frame.labels
    renumbered = np.where(truth > 0, truth + 100, 0).astype(np.int64)  # ids need not match; int64 converted
    s = clutterseg.score_frame(truth, renumbered)
    assert s.gt_objects == s.pred_objects == s.matched == len(frame.objects)
    assert (s.tp, s.fp, s.fn) == (1, 0, 0)
    assert s.overlap_f == s.boundary_f == s.detected_75 == 1
    empty = clutterseg.score_frame(np.zeros_like(truth), truth)
    assert not empty.scored and math.isnan(empty.overlap_f)
    with pytest.raises(ValueError, match="prediction: size 80x120 differs from the ground truth's 160x120"):
        clutterseg.score_frame(truth, truth[:, :80].copy())
    with pytest.raises(TypeError, match="labels are integer ids"):
        clutterseg.score_frame(truth, truth.astype(np.float32))
