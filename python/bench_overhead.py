#!/usr/bin/env python3
"""Per-frame overhead of the Python call against the C++ call, on the real dev frames.

Every call is timed twice at once: in Python around Segmenter.segment(depth, camera), and in C++ around
the clutterseg::Segmenter::segment call inside it (Result._core_window). Their difference is everything the
Python layer adds (argument checks, the array view, releasing and taking back the GIL, the Result
object) measured on the same call, so the pipeline's own frame-to-frame noise cancels out. Reading the
outputs (labels, points, normals, objects) is timed separately.

    PYTHONPATH=build/python /usr/bin/python3 python/bench_overhead.py [--repeats 20] [--threads 1]
"""
import argparse
import statistics
import sys
import time
from pathlib import Path

import clutterseg

DEV_SETS = ["osd-kinect", "tabletop-realsense", "ycbv-0000", "ycbv-0003"]


def main():
    here = Path(__file__).resolve().parent
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", default=here.parent.parent / "shared" / "data" / "dev", type=Path)
    parser.add_argument("--repeats", type=int, default=20, help="passes over every set (a stream each)")
    parser.add_argument("--threads", type=int, default=0, help="Params::threads (0 = all cores)")
    args = parser.parse_args()

    frames = {name: list(clutterseg.Dataset(args.data / name)) for name in DEV_SETS}
    count = sum(len(f) for f in frames.values())
    segmenter = clutterseg.Segmenter(threads=args.threads)
    per_frame = {}  # (set, frame) -> lists of python ms, core ms, outputs ms
    for _ in range(args.repeats):
        for name, stream in frames.items():
            segmenter.reset()
            for f in stream:
                start = time.perf_counter()
                result = segmenter.segment(f.depth, f.camera)
                python_ms = (time.perf_counter() - start) * 1e3
                start = time.perf_counter()
                result.object_labels, result.patch_labels, result.points, result.normals, result.objects
                outputs_ms = (time.perf_counter() - start) * 1e3
                entry = per_frame.setdefault((name, f.name), ([], [], []))
                entry[0].append(python_ms)
                core_start, core_end = result._core_window
                entry[1].append((core_end - core_start) * 1e3)
                entry[2].append(outputs_ms)

    def median_over_frames(pick):
        return statistics.median(statistics.median(pick(v)) for v in per_frame.values())

    python_ms = median_over_frames(lambda v: v[0])
    core_ms = median_over_frames(lambda v: v[1])
    overhead_ms = median_over_frames(lambda v: [p - c for p, c in zip(v[0], v[1])])
    outputs_ms = median_over_frames(lambda v: v[2])
    print(f"{count} dev frames x {args.repeats} passes, threads={args.threads}; medians over frames of the "
          f"per-frame medians")
    print(f"  Python call Segmenter.segment   {python_ms:8.3f} ms")
    print(f"  C++ call inside it              {core_ms:8.3f} ms")
    print(f"  overhead of the Python call     {overhead_ms * 1e3:8.1f} us  ({100 * overhead_ms / core_ms:.2f} %)")
    print(f"  reading labels, points, normals (interleaved copy), objects  {outputs_ms * 1e3:8.1f} us")
    return 0


if __name__ == "__main__":
    sys.exit(main())
