"""clutterseg: real-time segmentation of depth images of cluttered table-tops into object hypotheses
(Ueckermann, Haschke and Ritter, IROS 2013), with NumPy arrays in and out.

    import clutterseg
    frame = clutterseg.Dataset("examples/osd-test50")[0]
    result = clutterseg.Segmenter().segment(frame.depth, frame.camera)   # result.object_labels, .objects

Segmenter and Camera segment frames; Dataset and read_depth read frames; score_frame and evaluate score
any method's labels as `clutterseg eval` does; clutterseg.synth makes scenes with exact labels.
Arguments that are wrong raise TypeError or ValueError; failures the core reports (files, their
content) raise clutterseg.Error (a RuntimeError); every message is the core's one line. docs/PYTHON.md.
"""
from __future__ import annotations

import json
import math
import sys
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional, Union

try:
    from . import _clutterseg as _core
except ImportError as e:  # the source folder python/clutterseg has no compiled module
    raise ImportError(
        f"clutterseg's compiled module is missing in {Path(__file__).parent} ({e}); build it with scripts/build.sh and "
        "use PYTHONPATH=build/python, or install it with scripts/install_python.sh (docs/PYTHON.md)") from e

from ._clutterseg import (  # noqa: F401  (re-exported)
    SCORE_NAMES,
    Camera,
    Error,
    FrameScores,
    GraphEdge,
    HiddenObject,
    Object,
    OrientedBox,
    Patch,
    Plane,
    Result,
    boundary_tolerance_px,
    mean_std,
    object_boundaries,
    read_color,
    read_depth,
    read_labels,
    score_frame,
    synth,
    write_labels,
)

sys.modules[__name__ + ".synth"] = synth  # so that `import clutterseg.synth` works too

__all__ = [
    "Camera", "Segmenter", "Pipeline", "Result", "Object", "HiddenObject", "OrientedBox", "Patch", "GraphEdge", "Plane", "Error",
    "segment", "default_params", "Frame", "Dataset", "read_depth", "read_labels", "read_color", "write_labels",
    "FrameScores", "SCORE_NAMES", "score_frame", "boundary_tolerance_px", "object_boundaries", "mean_std",
    "FrameRecord", "Evaluation", "evaluate", "summarize", "synth",
]

_PARAMS_WHAT = "clutterseg.Segmenter params"
PathLike = Union[str, Path]


# ---- parameters --------------------------------------------------------------------------------------

def _json_value(key: str, value: Any) -> Any:
    """A value json can write; NumPy scalars become Python numbers. The core checks names, types, ranges."""
    if value is None or isinstance(value, (bool, int, float, str, list)):
        return value
    if hasattr(value, "item") and getattr(value, "ndim", None) == 0:  # numpy.float32(0.5), numpy.int64(3)
        return value.item()
    raise ValueError(f"{_PARAMS_WHAT}: parameter '{key}' must be a number or a bool, got {type(value).__name__}")


def _put(tree: dict, path: list[str], value: Any, key: str) -> None:
    """Sets tree[path[0]]...[path[-1]] = value; dict values merge into what is there."""
    node = tree
    for depth, part in enumerate(path[:-1]):
        child = node.setdefault(part, {})
        if not isinstance(child, dict):
            raise ValueError(f"{_PARAMS_WHAT}: '{key}' sets a field of '{'.'.join(path[:depth + 1])}', "
                             "which is given a value")
        node = child
    leaf = path[-1]
    if isinstance(value, Mapping):
        if not isinstance(node.setdefault(leaf, {}), dict):
            raise ValueError(f"{_PARAMS_WHAT}: '{key}' is given both a value and fields")
        for sub_key, sub_value in value.items():
            if not isinstance(sub_key, str):
                raise TypeError(f"{_PARAMS_WHAT}: parameter names are strings, got {sub_key!r} in '{key}'")
            full = f"{key}.{sub_key}"
            _put(node[leaf], sub_key.split("."), sub_value, full)
    else:
        node[leaf] = _json_value(key, value)


def _params_json(params: Optional[Mapping[str, Any]], keywords: Mapping[str, Any]) -> str:
    """Parameters as the JSON of `clutterseg --dump-config`: nested dicts, dotted keys ("graph.theta_c")
    and keywords (graph__theta_c=0.6, or graph={"theta_c": 0.6}) merged in that order, later ones winning."""
    if params is not None and not isinstance(params, Mapping):
        raise TypeError(f"{_PARAMS_WHAT}: expected a dict, got {type(params).__name__}")
    tree: dict = {}
    for key, value in (params or {}).items():
        if not isinstance(key, str):
            raise TypeError(f"{_PARAMS_WHAT}: parameter names are strings, got {key!r}")
        _put(tree, key.split("."), value, key)
    for key, value in keywords.items():
        dotted = key.replace("__", ".")
        _put(tree, dotted.split("."), value, dotted)
    return json.dumps(tree)


def _leaves(tree: dict, prefix: str = "") -> Iterator[tuple[str, Any]]:
    for key, value in tree.items():
        if isinstance(value, dict):
            yield from _leaves(value, f"{prefix}{key}.")
        else:
            yield f"{prefix}{key}", value


def _read_params(text: str) -> str:
    """The core reads the parameters (params_from_json: names, types, ranges). When its message does not
    say which parameter it refused, the core reads them one at a time to find it; nothing is checked here."""
    try:
        return _core._read_params(text)
    except ValueError as error:
        message = str(error)
        leaves = list(_leaves(json.loads(text)))
        if any(f"'{key}'" in message for key, _ in leaves):
            raise
        for key, value in leaves:
            single: dict = {}
            _put(single, key.split("."), value, key)
            try:
                _core._read_params(json.dumps(single))
            except ValueError as refused:
                reason = str(refused).removeprefix(f"{_PARAMS_WHAT}: ")
                raise ValueError(f"{_PARAMS_WHAT}: parameter '{key}': {reason}") from None
        raise


def default_params() -> dict:
    """Every parameter with its default, nested as `clutterseg --dump-config` prints it (units:
    include/clutterseg/params.hpp)."""
    return json.loads(_core._read_params("{}"))


class Segmenter(_core.Segmenter):
    """Segments depth frames into surface patches and object hypotheses; keeps the temporal-smoothing
    window of a stream between calls (reset() starts a new stream), as the C++ Segmenter does.

    Segmenter(params=None, /, **keywords)
      params: dict of parameters named as in `clutterseg --dump-config`, nested
              ({"graph": {"theta_c": 0.6}}) or with dotted keys ({"graph.theta_c": 0.6});
              missing ones keep their defaults (default_params() lists them with their values).
      keywords: the same names as keyword arguments; a nested name joins its parts with a double
              underscore (graph__theta_c=0.6), a group may be given as a dict (graph={"theta_c": 0.6}),
              top-level names as they are (seed=3, threads=1). Keywords win over params.
    Units are those of include/clutterseg/params.hpp: metres, degrees, pixels at 320x240 (scaled to the
    camera), frames. An unknown name, a wrong type or a value out of range raises ValueError naming it.

    segment(depth, camera) -> Result (see its help); params -> the parameters in effect, as a dict.
    """

    def __init__(self, params: Optional[Mapping[str, Any]] = None, /, **keywords: Any) -> None:
        super().__init__(_read_params(_params_json(params, keywords)))

    @property
    def params(self) -> dict:
        """The parameters in effect, every one of them, nested as `clutterseg --dump-config` prints them."""
        return json.loads(self._params_json)

    def __repr__(self) -> str:
        return "clutterseg.Segmenter(...)"


class Pipeline(_core.Pipeline):
    """Segments the frames of one stream on several cores at once, for throughput: while one frame is
    segmented the next ones are too, and Results come out in push order, each the same as
    Segmenter.segment gives for the same stream (docs/PYTHON.md, docs/BENCHMARKS.md "Threads").

    Pipeline(params=None, /, **keywords): parameters as for Segmenter; `threads` is the number of worker
    threads (0, the default: one per core, and a second frame only while a core is idle).

    push(depth, camera) queues a frame (read in place: do not write to the array until its Result is
    popped); pop() -> Result of the oldest frame; in_flight, capacity, workers; reset() starts a new
    stream. map(frames) does it all for an iterable of (depth, camera) pairs. Use one Pipeline from
    one Python thread.
    """

    def __init__(self, params: Optional[Mapping[str, Any]] = None, /, **keywords: Any) -> None:
        super().__init__(_read_params(_params_json(params, keywords)))

    def map(self, frames) -> Iterator[Result]:
        """Results of (depth, camera) pairs in their order, keeping up to `capacity` frames in flight.
        A frame without valid depth raises clutterseg.Error when its turn comes."""
        for depth, camera in frames:
            if self.in_flight >= self.capacity:
                yield self.pop()
            self.push(depth, camera)
        while self.in_flight:
            yield self.pop()

    def __repr__(self) -> str:
        return f"clutterseg.Pipeline(workers={self.workers})"


def segment(depth, camera: Camera, params: Optional[Mapping[str, Any]] = None, /, **keywords: Any) -> Result:
    """One frame on its own, without temporal smoothing (a fresh Segmenter with smoothing.temporal off).
    Arguments as Segmenter(params, **keywords) and Segmenter.segment(depth, camera)."""
    return Segmenter(params, **{**keywords, "smoothing__temporal": False}).segment(depth, camera)


# ---- dataset frames ---------------------------------------------------------------------------------

@dataclass
class Frame:
    """One frame of a dataset folder."""
    name: str                 # file stem, e.g. "000001"
    depth: Any                # uint16 (H, W) in steps of camera.depth_unit_m, 0 = no measurement
    color: Optional[Any]      # uint8 (H, W, 3) RGB, or None (missing or another size)
    label: Optional[Any]      # int32 (H, W) ground-truth ids, 0 = not an object, or None
    camera: Camera
    path: Path                # the depth file
    family: str = "all"       # what eval groups by (scenes.json), "all" without one
    scene: str = ""           # frames of one scene share a temporal window in evaluate()


class Dataset:
    """A dataset folder (SPEC Sec. 3): camera.json, depth/NAME.png (uint16, mm), optional color/NAME.png
    and label/NAME.png, optional scenes.json (families and scenes). Frames are in name (= time) order;
    dataset[i] or dataset["NAME"] reads one, iterating reads them all.

    Dataset(path, camera=None, sequence=False)
      camera: Camera to use instead of path/camera.json
      sequence: all frames are one scene (`clutterseg eval --sequence`) unless scenes.json names scenes
    """

    def __init__(self, path: PathLike, camera: Optional[Camera] = None, sequence: bool = False) -> None:
        self.path = Path(path)
        self._files = _core._list_dataset(str(self.path))
        self.names = [f[0] for f in self._files]
        if camera is None and (self.path / "camera.json").exists():
            camera = Camera.from_json(str(self.path / "camera.json"))
        self.camera = camera
        self._groups = self._read_groups(sequence)

    def __len__(self) -> int:
        return len(self._files)

    def __iter__(self) -> Iterator[Frame]:
        return (self[i] for i in range(len(self)))

    def __getitem__(self, key: Union[int, str]) -> Frame:
        if isinstance(key, str):
            if key not in self.names:
                raise KeyError(f"{self.path}: no frame named {key!r}")
            key = self.names.index(key)
        name, depth, color, label = self._files[key]
        if self.camera is None:
            raise Error(f"{depth}: no intrinsics; the dataset has no camera.json (give Dataset(path, camera=...))")
        depth_image, color_image, label_image = _core._load_frame(depth, color, label, self.camera)
        family, scene = self._groups[name]
        return Frame(name, depth_image, color_image, label_image, self.camera, Path(depth), family, scene)

    def _read_groups(self, sequence: bool) -> dict[str, tuple[str, str]]:
        """Family and scene of every frame, from scenes.json {"frames": [{"name", "family", "scene"?}]}
        as `clutterseg eval` reads it: without it every frame is its own scene (or all one with
        sequence); frames it does not list are family "unlisted"."""
        groups = {name: ("all", "sequence" if sequence else name) for name in self.names}
        file = self.path / "scenes.json"
        if not file.exists():
            return groups
        try:
            info = json.loads(file.read_text())
        except ValueError:
            raise Error(f"{file}: is not valid JSON") from None
        if not isinstance(info, dict) or not isinstance(info.get("frames"), list):
            raise Error(f'{file}: expected {{"frames": [{{"name": ..., "family": ...}}, ...]}}')
        groups = {name: ("unlisted", scene) for name, (_, scene) in groups.items()}
        for entry in info["frames"]:
            if not isinstance(entry, dict) or not isinstance(entry.get("name"), str):
                raise Error(f'{file}: every frame needs a "name"')
            name = entry["name"]
            if name not in groups:
                continue
            family = entry["family"] if isinstance(entry.get("family"), str) else "all"
            scene = groups[name][1]
            value = entry.get("scene")
            if isinstance(value, str):
                scene = value
            elif isinstance(value, (int, float)) and not isinstance(value, bool):
                scene = json.dumps(value)
            groups[name] = (family, scene)
        return groups


# ---- evaluation --------------------------------------------------------------------------------------

@dataclass
class FrameRecord:
    """One scored frame of evaluate()."""
    frame: str
    family: str
    scene: str
    scores: Optional[FrameScores]  # None when the frame failed
    error: str = ""                # the one-line message of a failed frame

    @property
    def failed(self) -> bool:
        return bool(self.error)


def _number_or_none(value: float) -> Optional[float]:
    return value if math.isfinite(value) else None


def summarize(frames: list[FrameRecord]) -> list[dict]:
    """Groups "all", then each family in first-seen order, in the form of summary.json's "groups":
    per scene the mean over its frames, then mean and population std over scenes (NaN ignored;
    None where undefined), as `clutterseg eval` summarises."""
    families = ["all"]
    for f in frames:
        if f.family != "all" and f.family not in families:
            families.append(f.family)
    groups = []
    for family in families:
        group = {"family": family, "frames": 0, "scenes": 0, "failed": 0, "unscored": 0, "scores": {}}
        scenes: dict[str, list[FrameScores]] = {}
        for f in frames:
            if family != "all" and f.family != family:
                continue
            if f.failed:
                group["failed"] += 1
            elif not f.scores.scored:
                group["unscored"] += 1
            else:
                group["frames"] += 1
                scenes.setdefault(f.scene, []).append(f.scores)
        group["scenes"] = len(scenes)
        for name in SCORE_NAMES:
            scene_means = [mean_std([getattr(s, name) for s in scenes[scene]])[0] for scene in sorted(scenes)]
            mean, std, count = mean_std(scene_means)
            group["scores"][name] = {"mean": _number_or_none(mean), "std": _number_or_none(std), "scenes": count}
        groups.append(group)
    return groups


@dataclass
class Evaluation:
    """What evaluate() found: every frame's scores, and the summary groups (summary.json's form)."""
    frames: list[FrameRecord]
    groups: list[dict]

    def mean(self, score: str, family: str = "all") -> Optional[float]:
        """Mean over scenes of one score (a name of SCORE_NAMES) in a family, None when undefined."""
        for g in self.groups:
            if g["family"] == family:
                return g["scores"][score]["mean"]
        raise KeyError(f"no family {family!r}")


def evaluate(dataset: Union[Dataset, PathLike], predict: Callable[[Frame], Any], *,
             reset: Optional[Callable[[], None]] = None, sequence: bool = False) -> Evaluation:
    """Scores a method on a labelled dataset as `clutterseg eval DATASET` scores clutterseg.

      predict(frame) -> labels: the method; int (H, W) ids, 0 = not an object (no table, no background)
      reset(): called when a new scene starts (a temporal window must not span two scenes)
      sequence: without scenes.json, all frames are one scene (as `--sequence`); when `dataset` is a
                path (a Dataset given keeps its own)
    A frame whose reading or prediction raises clutterseg.Error or ValueError is recorded as failed
    and the run goes on. For clutterseg itself (what eval runs):
        seg = clutterseg.Segmenter(support__objects_only=True)
        evaluate(path, lambda f: seg.segment(f.depth, f.camera).objects_only_labels, reset=seg.reset)
    """
    if not isinstance(dataset, Dataset):
        dataset = Dataset(dataset, sequence=sequence)
    records = []
    scene = None
    for i, name in enumerate(dataset.names):
        family, frame_scene = dataset._groups[name]
        if scene is not None and frame_scene != scene and reset is not None:
            reset()
        scene = frame_scene
        record = FrameRecord(name, family, frame_scene, None)
        try:
            frame = dataset[i]
            if frame.label is None:
                raise Error(f"{dataset.path / 'label' / (name + '.png')}: no ground truth for this frame")
            record.scores = score_frame(frame.label, predict(frame))
        except (Error, ValueError) as e:
            record.error = str(e)
        records.append(record)
    return Evaluation(records, summarize(records))
