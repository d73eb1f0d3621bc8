#!/usr/bin/python3
"""Writes the seed corpus of the fuzzers into fuzz/corpus/NAME/ (small valid inputs of every reader,
plus the regression inputs of tests/data/bad-inputs). Run from anywhere; needs python3-opencv, numpy."""
import json
import pathlib
import shutil
import struct

import cv2
import numpy as np

here = pathlib.Path(__file__).resolve().parent
root = here.parent
bad = root / "tests" / "data" / "bad-inputs"
out = here / "corpus"
shutil.rmtree(out, ignore_errors=True)
for name in ["depth_png", "label_png", "camera_json", "config_json", "pcd", "segmenter"]:
    (out / name).mkdir(parents=True)


def png(path, image):
    ok, data = cv2.imencode(".png", image)
    assert ok
    path.write_bytes(data.tobytes())


# A small table-top: a plane sloping away with a box on it, 32x24, millimetres.
ys, xs = np.mgrid[0:24, 0:32]
scene = (800 + 10 * ys).astype(np.uint16)
scene[8:16, 10:20] -= 60
scene[0, 0] = 0
png(out / "depth_png" / "scene.png", scene)
png(out / "depth_png" / "eight-bit.png", (scene // 8).astype(np.uint8))
shutil.copy(bad / "depth-64x48.png", out / "depth_png" / "depth-64x48.png")
for f in ["depth-png-slow.png", "depth-png-slow-2.png", "depth-png-slow-3.png", "png-declared-1e6x1e6.png"]:
    shutil.copy(bad / f, out / "depth_png" / f)

labels = np.zeros((24, 32), np.uint16)
labels[8:16, 10:20] = 1
labels[0:8, :] = 2
labels[16:24, 20:32] = 3 + (xs[16:24, 20:32] % 3)
png(out / "label_png" / "labels16.png", labels)
png(out / "label_png" / "labels8.png", labels.astype(np.uint8))
for f in (bad / "eval-many-ids").glob("*/*.png"):
    shutil.copy(f, out / "label_png" / f"many-ids-{f.parent.name}.png")

camera = {"fx": 525.0, "fy": 525.0, "cx": 319.5, "cy": 239.5, "width": 640, "height": 480, "depth_unit_m": 0.001}
(out / "camera_json" / "kinect.json").write_text(json.dumps(camera))
for f in bad.glob("camera-*.json"):
    shutil.copy(f, out / "camera_json" / f.name)

(out / "config_json" / "partial.json").write_text('{"graph": {"theta_c": 0.6}, "threads": 1, "seed": 7}')
for f in bad.glob("config-*.json"):
    shutil.copy(f, out / "config_json" / f.name)

# Organized 8x6 clouds of a plane at 1 m seen by fx = fy = 8 (ascii and binary), a NaN, rgb on one.
w, h, f = 8, 6, 8.0
pts = []
for v in range(h):
    for u in range(w):
        z = 1.0 + 0.01 * v
        pts.append(((u - 3.5) * z / f, (v - 2.5) * z / f, z))
pts[5] = (float("nan"),) * 3
head = "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH %d\nHEIGHT %d\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS %d\n" % (w, h, w * h)
(out / "pcd" / "ascii.pcd").write_text(head + "DATA ascii\n" + "".join("%g %g %g\n" % p for p in pts))
(out / "pcd" / "binary.pcd").write_bytes((head + "DATA binary\n").encode() + b"".join(struct.pack("<3f", *p) for p in pts))
head_rgb = head.replace("FIELDS x y z", "FIELDS x y z rgb").replace("SIZE 4 4 4", "SIZE 4 4 4 4").replace(
    "TYPE F F F", "TYPE F F F U").replace("COUNT 1 1 1", "COUNT 1 1 1 1")
(out / "pcd" / "rgb.pcd").write_bytes((head_rgb + "DATA binary\n").encode() +
                                      b"".join(struct.pack("<3fI", *p, 0x00ff8040) for p in pts))
for p in list(bad.glob("pcd-*.pcd")) + list((bad / "pcd-fuzzed-more").glob("*.pcd")):
    shutil.copy(p, out / "pcd" / p.name)

# Segmenter inputs (fuzz_segmenter.cpp's layout): intrinsics, sizes, switches, then depth.
def frame(fx, w, h, depth, switches=0x3f, extra=(11, 5, 2, 50, 20, 6, 20, 50, 7, 1)):
    head = struct.pack("<6d", fx, fx, (w - 1) / 2, (h - 1) / 2, 0.001, 0.5)
    b = bytes([w - 1, h - 1, switches]) + bytes(e & 0xFF for e in extra)
    b = b + bytes(16 - len(b))
    return head + b + depth.astype("<u2").tobytes()

(out / "segmenter" / "scene.bin").write_bytes(frame(26.0, 32, 24, scene))
(out / "segmenter" / "scene-no-temporal.bin").write_bytes(frame(26.0, 32, 24, scene, 0x3e))
(out / "segmenter" / "noise.bin").write_bytes(frame(40.0, 48, 40, np.random.default_rng(1).integers(500, 2000, 48 * 40)))
(out / "segmenter" / "fx-huge.bin").write_bytes(frame(1e10, 32, 24, scene))
print("corpus written to", out)
