#!/usr/bin/env python3
"""Frames per second of a stream from Python: Segmenter.segment frame after frame against Pipeline.map.

The dev set's frames are cycled into a stream of at least --frames frames; the two are run in turn
(--passes times each, interleaved so that both see the same machine load) and the median pass is
reported, with the process's CPU time per frame (which a busy host inflates less than wall time).

    PYTHONPATH=build/python /usr/bin/python3 python/bench/pipeline.py [--set osd-kinect] [--passes 5]
"""
import argparse
import statistics
import time
from pathlib import Path

import clutterseg


def run(make_results, frames):
    wall, cpu = time.perf_counter(), time.process_time()
    count = sum(1 for _ in make_results(frames))
    return count / (time.perf_counter() - wall), 1000 * (time.process_time() - cpu) / count


def main():
    here = Path(__file__).resolve().parent
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", default=here.parents[2] / "shared" / "data" / "dev", type=Path)
    parser.add_argument("--set", default="osd-kinect", help="dev set to stream (default osd-kinect)")
    parser.add_argument("--frames", type=int, default=60, help="frames per pass (the set cycled)")
    parser.add_argument("--passes", type=int, default=5, help="passes per configuration")
    args = parser.parse_args()

    loaded = [(f.depth, f.camera) for f in clutterseg.Dataset(args.data / args.set)]
    frames = [loaded[i % len(loaded)] for i in range(max(args.frames, len(loaded)))]
    configs = {
        "Segmenter, threads 1": lambda fs: (s.segment(d, c) for s in [clutterseg.Segmenter(threads=1)] for d, c in fs),
        "Segmenter, default": lambda fs: (s.segment(d, c) for s in [clutterseg.Segmenter()] for d, c in fs),
        "Pipeline, default": lambda fs: clutterseg.Pipeline().map(fs),
        "Pipeline, 2 workers": lambda fs: clutterseg.Pipeline(threads=2).map(fs),
    }
    runs = {name: [] for name in configs}
    for _ in range(args.passes):
        for name, make in configs.items():
            runs[name].append(run(make, frames))
    base = statistics.median(fps for fps, _ in runs["Segmenter, threads 1"])
    print(f"{args.set}: {len(frames)} frames per pass, {args.passes} passes, median pass")
    print("| configuration | frames/s | vs Segmenter, 1 thread | CPU ms/frame |")
    print("|---|---:|---:|---:|")
    for name, values in runs.items():
        fps = statistics.median(v[0] for v in values)
        cpu = statistics.median(v[1] for v in values)
        print(f"| {name} | {fps:.1f} | {fps / base:.2f}x | {cpu:.1f} |")


if __name__ == "__main__":
    main()
