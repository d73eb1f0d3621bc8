#!/usr/bin/env python3
"""Per-frame overhead of the Python call against the C++ call, on the real dev frames.

Every call is timed twice at once: in Python around Segmenter.segment(depth, camera), and in C++ around
the clutterseg::Segmenter::segment call inside it (Result._core_window, Result._core_cpu_window). The
difference is everything the Python layer adds (argument checks, the array view, releasing and taking
back the GIL, the Result object), measured on the same call, so the pipeline's frame-to-frame noise
cancels out. Two clocks: wall time (what a user waits) and the calling thread's CPU time (which the
load of a shared host does not inflate). The previous Result is freed before the timer starts, as a C++
loop frees it outside its segment() call. Reading the outputs is timed separately.

    PYTHONPATH=build/python /usr/bin/python3 python/bench/overhead.py [--repeats 20] [--threads 1]
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
    parser.add_argument("--data", default=here.parents[2] / "shared" / "data" / "dev", type=Path)
    parser.add_argument("--repeats", type=int, default=20, help="passes over every set (a stream each)")
    parser.add_argument("--threads", type=int, default=0, help="Params::threads (0 = the idle cores but one)")
    args = parser.parse_args()

    frames = {name: list(clutterseg.Dataset(args.data / name)) for name in DEV_SETS}
    count = sum(len(f) for f in frames.values())
    segmenter = clutterseg.Segmenter(threads=args.threads)
    samples = {}  # (set, frame) -> {measure: [ms, ...]}
    for _ in range(args.repeats):
        for name, stream in frames.items():
            segmenter.reset()
            for f in stream:
                result = None  # free the previous frame's buffers outside the timed call
                wall, cpu = time.perf_counter(), time.thread_time()
                result = segmenter.segment(f.depth, f.camera)
                wall, cpu = time.perf_counter() - wall, time.thread_time() - cpu
                read = time.perf_counter()
                result.object_labels, result.patch_labels, result.points, result.normals, result.objects
                read = time.perf_counter() - read
                core_wall = result._core_window[1] - result._core_window[0]
                core_cpu = result._core_cpu_window[1] - result._core_cpu_window[0]
                s = samples.setdefault((name, f.name), {})
                for key, seconds in [("python", wall), ("core", core_wall), ("overhead", wall - core_wall),
                                     ("overhead_cpu", cpu - core_cpu), ("read", read)]:
                    s.setdefault(key, []).append(seconds * 1e3)

    def median_over_frames(key):
        return statistics.median(statistics.median(s[key]) for s in samples.values())

    core = median_over_frames("core")
    print(f"{count} dev frames x {args.repeats} passes, threads={args.threads}; median over frames of the "
          f"per-frame medians")
    print(f"  Python call Segmenter.segment            {median_over_frames('python'):9.3f} ms")
    print(f"  C++ call inside it                       {core:9.3f} ms")
    overhead = median_over_frames("overhead")
    print(f"  overhead of the Python call, wall time   {overhead * 1e3:9.1f} us ({100 * overhead / core:.2f} %)")
    print(f"  overhead of the Python call, CPU time    {median_over_frames('overhead_cpu') * 1e3:9.1f} us")
    print(f"  reading labels, points, normals (the one copy) and objects  {median_over_frames('read') * 1e3:.1f} us")
    return 0


if __name__ == "__main__":
    sys.exit(main())
