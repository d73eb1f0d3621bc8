#!/usr/bin/python3
"""Plots the soak benchmark's CSV (bench/soak.cpp): resident memory and frame time over the frames.
Usage: scripts/soak_plot.py SOAK.csv OUT.png"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

rows = list(csv.DictReader(open(sys.argv[1])))
frame = [int(r["frame"]) for r in rows]
rss = [float(r["rss_mb"]) for r in rows]
median = [float(r["median_ms"]) for r in rows]
fig, (a, b) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
a.plot(frame, rss, lw=1)
a.set_ylabel("resident memory [MB]")
a.set_ylim(0, max(rss) * 1.15)
a.grid(alpha=0.3)
a.set_title("soak: %d frames through one Segmenter (temporal smoothing on)" % frame[-1])
b.plot(frame, median, lw=0.8, color="tab:orange")
b.set_ylabel("median frame time\nper block [ms]")
b.set_xlabel("frame")
b.set_ylim(0, max(median) * 1.15)
b.grid(alpha=0.3)
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=90)
