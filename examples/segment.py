#!/usr/bin/env python3
"""Segments one frame with clutterseg and shows it and its objects with matplotlib.

    .venv/bin/python3 examples/segment.py                       # the bundled examples/osd-test50
    .venv/bin/python3 examples/segment.py ../shared/data/dev/ycbv-0000 --frame 000004 --out objects.png

Without a display (or with --out) the figure is written to a PNG instead of shown.
"""
import argparse
import os
import sys
from pathlib import Path

import matplotlib
import numpy as np

import clutterseg


def project(point, camera):
    """Image position (u, v) [px] of a camera-frame point [m]."""
    x, y, z = point
    return camera.fx * x / z + camera.cx, camera.fy * y / z + camera.cy


def object_colours(count, seed=3):
    rng = np.random.default_rng(seed)
    colours = rng.uniform(0.25, 1.0, size=(count + 1, 3))
    colours[0] = 0
    return colours


def main():
    here = Path(__file__).resolve().parent
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("dataset", nargs="?", default=here / "osd-test50",
                        help="dataset folder (camera.json, depth/NAME.png, optional color/)")
    parser.add_argument("--frame", help="frame name (default: the first)")
    parser.add_argument("--out", help="write the figure to this PNG instead of showing it")
    args = parser.parse_args()

    if args.out or not os.environ.get("DISPLAY"):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dataset = clutterseg.Dataset(args.dataset)
    frame = dataset[args.frame] if args.frame else dataset[0]
    result = clutterseg.Segmenter().segment(frame.depth, frame.camera)
    labels = result.object_labels
    objects = [o for o in result.objects if not (o.support or o.background)]
    print(f"{frame.name}: {len(objects)} objects, {len(result.objects) - len(objects)} support/background "
          f"surfaces, {result.timings_ms['total']:.1f} ms")
    for o in objects:
        x, y, z = o.centroid
        print(f"  object {o.id:3d}: {o.pixel_count:6d} px, centroid ({x:+.3f}, {y:+.3f}, {z:.3f}) m, "
              f"box {' x '.join(f'{e * 100:.1f}' for e in o.box.extents)} cm, cut cost {o.cut_cost:.2f}")

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.4))
    photo = frame.color if frame.color is not None else None
    if photo is not None:
        axes[0].imshow(photo)
        axes[0].set_title(f"{frame.name}: colour")
    else:
        axes[0].set_title(f"{frame.name}: no colour image")
    depth_m = frame.depth.astype(np.float32) * frame.camera.depth_unit_m
    valid = depth_m[depth_m > 0]
    near, far = np.percentile(valid, [1, 99]) if valid.size else (0, 1)
    shown = axes[1].imshow(np.where(depth_m > 0, depth_m, np.nan), cmap="viridis", vmin=near, vmax=far)
    fig.colorbar(shown, ax=axes[1], fraction=0.035, label="depth [m]")
    axes[1].set_title("depth")

    colours = object_colours(int(labels.max()))
    overlay = colours[labels]
    for o in result.objects:  # the table and walls in grey
        if o.support or o.background:
            overlay[labels == o.id] = 0.35
    base = photo.astype(np.float32) / 255 if photo is not None else np.repeat(
        (depth_m / max(depth_m.max(), 1e-6))[..., None], 3, axis=2)
    blended = np.where(labels[..., None] > 0, 0.35 * base + 0.65 * overlay, base)
    blended[clutterseg.object_boundaries(labels) > 0] = 1  # white outlines
    axes[2].imshow(blended)
    for o in objects:  # centroids are in the camera frame (no Camera.camera_to_robot set)
        u, v = project(o.centroid, frame.camera)
        axes[2].text(u, v, str(o.id), color="white", fontsize=8, ha="center", va="center",
                     bbox=dict(boxstyle="round,pad=0.15", fc="black", alpha=0.6, lw=0))
    axes[2].set_title(f"{len(objects)} objects (table and walls grey)")
    for ax in axes:
        ax.set_axis_off()
    fig.tight_layout()

    if matplotlib.get_backend().lower() == "agg":
        out = Path(args.out or "out/segment.png")
        out.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(out, dpi=100)
        print(f"wrote {out}")
    else:
        plt.show()
    return 0


if __name__ == "__main__":
    sys.exit(main())
