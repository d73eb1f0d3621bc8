#!/usr/bin/python3
"""Hand labelling of a dataset frame from a small JSON spec: polygons drawn on the colour image, cut by
depth (height above the fitted table plane, depth continuity), so that the boundaries come from the
sensor, not from the polygon, wherever the depth shows them.

usage: scripts/label_frame.py DATASET NAME SPEC.json OUT_LABEL.png [--preview OUT.png]

SPEC (pixel coordinates of the 640x480 image):
  {"table": [[[x, y], ...], ...],       polygons of table only: the support plane is fitted there (RANSAC);
                                        pick them all around the objects (a Kinect's depth bends a little)
   "min_height": 0.006,                 object pixels lie higher than this above the table [m] (default 6 mm)
   "objects": [{"name": "mug",
                "polygon": [[x, y], ...],   generous outline; where two objects touch, the shared edge
                "seeds": [[x, y], ...],     optional: keep only the depth-continuous parts holding these
                "min_height": 0.0}],        optional per object (e.g. a flat lid: 0.002)
   "min_part": 40}                      depth-continuous parts of an object smaller than this [px] are
                                        dropped (flying pixels at silhouettes belong to no surface)
Objects are painted in list order: a later object wins where polygons overlap (list occluders last).
Ids are 1.. in list order. Pixels without depth are never labelled (as in the dataset's convention).
Needs Debian's python3-numpy and python3-opencv.
"""
import json
import sys

import cv2
import numpy as np


def points_of(depth_m, cam):
    h, w = depth_m.shape
    xs, ys = np.meshgrid(np.arange(w), np.arange(h))
    return np.dstack(((xs - cam["cx"]) * depth_m / cam["fx"], (ys - cam["cy"]) * depth_m / cam["fy"], depth_m))


def fit_table(pts, valid, mask, rng):
    sample = pts[valid & mask]
    if len(sample) < 100:
        sys.exit("table polygon holds fewer than 100 depth pixels")
    best, best_count = None, -1
    for _ in range(300):
        a, b, c = sample[rng.choice(len(sample), 3, replace=False)]
        n = np.cross(b - a, c - a)
        if np.linalg.norm(n) < 1e-9:
            continue
        n /= np.linalg.norm(n)
        count = np.count_nonzero(np.abs((sample - a) @ n) < 0.005)
        if count > best_count:
            best, best_count = (n, a), count
    n, a = best
    inliers = sample[np.abs((sample - a) @ n) < 0.005]
    centre = inliers.mean(axis=0)
    n = np.linalg.svd(inliers - centre, full_matrices=False)[2][2]
    if n @ centre > 0:  # normal towards the camera: heights above the table are positive
        n = -n
    return n, centre


def main(argv):
    if len(argv) < 5:
        sys.exit(__doc__)
    dataset, name, spec_path, out = argv[1:5]
    preview = argv[argv.index("--preview") + 1] if "--preview" in argv else None
    spec = json.load(open(spec_path))
    cam = json.load(open(f"{dataset}/camera.json"))
    depth = cv2.imread(f"{dataset}/depth/{name}.png", cv2.IMREAD_UNCHANGED)
    if depth is None or depth.dtype != np.uint16:
        sys.exit(f"{dataset}/depth/{name}.png: not a 16-bit depth PNG")
    depth_m = depth.astype(np.float64) * cam.get("depth_unit_m", 0.001)
    valid = depth > 0
    pts = points_of(depth_m, cam)
    h, w = depth.shape

    def polygon_mask(poly):
        m = np.zeros((h, w), np.uint8)
        cv2.fillPoly(m, [np.array(poly, np.int32)], 1)
        return m.astype(bool)

    table = np.zeros((h, w), bool)
    for poly in spec["table"]:
        table |= polygon_mask(poly)
    normal, centre = fit_table(pts, valid, table, np.random.default_rng(1))
    height = (pts - centre) @ normal
    # Surface normals (cross product of smoothed neighbours): a steep face touching the table keeps its
    # lowest millimetres, which the height alone would give to the table.
    smooth = points_of(cv2.GaussianBlur(depth_m.astype(np.float32), (5, 5), 0).astype(np.float64), cam)
    n = np.cross(np.gradient(smooth, axis=1), np.gradient(smooth, axis=0))
    n /= np.maximum(np.linalg.norm(n, axis=2, keepdims=True), 1e-12)
    steep = np.abs(n @ normal) < np.cos(np.radians(40))
    labels = np.zeros((h, w), np.uint16)
    jump = 0.02 + 0.02 * depth_m
    steps = np.zeros((h, w), bool)
    steps[:, 1:] |= np.abs(np.diff(depth_m, axis=1)) > jump[:, 1:]
    steps[1:, :] |= np.abs(np.diff(depth_m, axis=0)) > jump[1:, :]
    default_min = spec.get("min_height", 0.006)
    for k, obj in enumerate(spec["objects"], start=1):
        inside = polygon_mask(obj["polygon"]) & valid
        m = inside & (height > obj.get("min_height", default_min))
        m |= inside & steep & (height > 0.0015) & (cv2.dilate(m.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0)
        # Depth-continuous parts: the mask cut where the depth jumps, then 4-connected components.
        comp_input = m.astype(np.uint8)
        comp_input[steps] = 0
        count, comp, stats, _ = cv2.connectedComponentsWithStats(comp_input, connectivity=4)
        small = np.nonzero(stats[:, cv2.CC_STAT_AREA] < spec.get("min_part", 40))[0]
        m &= ~np.isin(comp, small[small > 0])
        if "seeds" in obj:
            keep = np.zeros((h, w), np.uint8)
            for x, y in obj["seeds"]:
                if comp[y, x] > 0:
                    keep |= (comp == comp[y, x]).astype(np.uint8)
                else:
                    print(f"{name}: seed {x},{y} of {obj['name']} is on no object pixel", file=sys.stderr)
            m = keep.astype(bool)
        labels[m] = k
    cv2.imwrite(out, labels)
    if preview:
        color = cv2.imread(f"{dataset}/color/{name}.png")
        rng = np.random.default_rng(7)
        palette = rng.integers(60, 255, (len(spec["objects"]) + 1, 3)).astype(np.uint8)
        palette[0] = 0
        view = (0.45 * color + 0.55 * palette[labels]).astype(np.uint8)
        view[labels == 0] = (color[labels == 0] * 0.5).astype(np.uint8)
        edges = cv2.morphologyEx(labels, cv2.MORPH_GRADIENT, np.ones((3, 3), np.uint8)) > 0
        view[edges] = (255, 255, 255)
        for k, obj in enumerate(spec["objects"], start=1):
            ys, xs = np.nonzero(labels == k)
            if len(xs):
                cv2.putText(view, f"{k} {obj['name']}", (int(xs.mean()) - 20, int(ys.mean())),
                            cv2.FONT_HERSHEY_SIMPLEX, 0.4, (255, 255, 255), 1)
        cv2.imwrite(preview, np.hstack([color, view]))
    print(f"{out}: {len(spec['objects'])} objects, table normal {np.round(normal, 3).tolist()}")


if __name__ == "__main__":
    main(sys.argv)
