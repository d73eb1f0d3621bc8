#!/usr/bin/python3
"""Writes a ROS 1 bag from a clutterseg dataset folder, so recorded frames can be replayed into the node.

  write_bag.py DATASET OUT.bag [--rate 30] [--float] [--no-color] [--start 1000000000]

DATASET is the layout of `clutterseg segment` (SPEC Sec. 3): camera.json, depth/NAME.png (uint16,
depth_unit_m metres per step, 0 = none), optional color/NAME.png. Frames go in name order, one every
1/rate seconds from --start, each as a depth image (16UC1 in mm, as openni2_camera publishes it; 32FC1 in
metres with --float or when depth_unit_m is not 1 mm) with its CameraInfo (K from camera.json, no
distortion), plus the colour image and its CameraInfo when there is one of the depth's size (registered
to depth: same intrinsics and frame id). Header stamps equal the bag's
record times; header.seq is the frame's index. The bag is written to a temporary file and renamed, so a
failure leaves no bag. Needs Debian's /usr/bin/python3 with python3-rosbag and python3-opencv.
"""
import argparse
import json
import os
import sys

import cv2
import numpy as np
import rosbag
import rospy
from sensor_msgs.msg import CameraInfo, Image


class DatasetError(Exception):
    """A problem with the input, reported as one line naming the file."""


def read_camera(path):
    try:
        with open(path) as f:
            cam = json.load(f)
        fx, fy, cx, cy = (float(cam[k]) for k in ("fx", "fy", "cx", "cy"))
        width, height = int(cam["width"]), int(cam["height"])
        unit = float(cam.get("depth_unit_m", 0.001))
    except OSError as e:
        raise DatasetError(f"{path}: cannot be read ({e.strerror})")
    except (ValueError, KeyError, TypeError) as e:
        raise DatasetError(f"{path}: needs numbers fx, fy, cx, cy, width, height ({e})")
    if not (fx > 0 and fy > 0 and width > 0 and height > 0 and unit > 0):
        raise DatasetError(f"{path}: fx, fy, width, height and depth_unit_m must be positive")
    return fx, fy, cx, cy, width, height, unit


def camera_info(header, intrinsics):
    fx, fy, cx, cy, width, height, _ = intrinsics
    info = CameraInfo()
    info.header = header
    info.width, info.height = width, height
    info.distortion_model = "plumb_bob"
    info.D = [0.0] * 5
    info.K = [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0]
    info.R = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    info.P = [fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0]
    return info


def image_message(header, array, encoding):
    msg = Image()
    msg.header = header
    msg.height, msg.width = array.shape[:2]
    msg.encoding = encoding
    msg.is_bigendian = 0
    msg.step = array.strides[0]
    msg.data = np.ascontiguousarray(array).tobytes()
    return msg


def frames(dataset):
    depth_dir = os.path.join(dataset, "depth")
    if not os.path.isdir(depth_dir):
        raise DatasetError(f"{dataset}: no depth/ folder (expected camera.json and depth/NAME.png)")
    names = sorted(f[:-4] for f in os.listdir(depth_dir) if f.endswith(".png"))
    if not names:
        raise DatasetError(f"{depth_dir}: holds no .png depth images")
    return names


def write_bag(args):
    intrinsics = read_camera(os.path.join(args.dataset, "camera.json"))
    width, height, unit = intrinsics[4], intrinsics[5], intrinsics[6]
    as_float = args.float or unit != 0.001
    names = frames(args.dataset)
    tmp = args.out + ".tmp"
    try:
        with rosbag.Bag(tmp, "w") as bag:
            for i, name in enumerate(names):
                path = os.path.join(args.dataset, "depth", name + ".png")
                depth = cv2.imread(path, cv2.IMREAD_UNCHANGED)
                if depth is None or depth.dtype != np.uint16 or depth.ndim != 2:
                    raise DatasetError(f"{path}: not a 16-bit single-channel PNG")
                if depth.shape != (height, width):
                    raise DatasetError(f"{path}: is {depth.shape[1]}x{depth.shape[0]}, camera.json says {width}x{height}")
                stamp = rospy.Time.from_sec(args.start + i / args.rate)
                header = rospy.Header(seq=i, stamp=stamp, frame_id=args.frame_id)
                if as_float:  # the library's own conversion: float32(value) * float32(unit)
                    image = image_message(header, depth.astype(np.float32) * np.float32(unit), "32FC1")
                else:
                    image = image_message(header, depth, "16UC1")
                bag.write(args.depth_topic, image, stamp)
                bag.write(topic_beside(args.depth_topic, "camera_info"), camera_info(header, intrinsics), stamp)
                color_path = os.path.join(args.dataset, "color", name + ".png")
                if args.color_topic and os.path.exists(color_path):
                    color = cv2.imread(color_path, cv2.IMREAD_COLOR)
                    if color is None:
                        raise DatasetError(f"{color_path}: cannot be read as a colour image")
                    if color.shape[:2] == depth.shape:  # registered to depth: the same intrinsics and frame
                        bag.write(args.color_topic, image_message(header, color, "bgr8"), stamp)
                        bag.write(topic_beside(args.color_topic, "camera_info"), camera_info(header, intrinsics), stamp)
        os.replace(tmp, args.out)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    return len(names)


def topic_beside(image_topic, name):
    """The CameraInfo topic image_transport pairs with an image topic: same namespace."""
    return image_topic.rsplit("/", 1)[0] + "/" + name


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dataset", help="folder with camera.json and depth/ (color/ optional)")
    parser.add_argument("out", help="bag file to write")
    parser.add_argument("--rate", type=float, default=30.0, help="frames per second (default 30)")
    parser.add_argument("--start", type=float, default=1e9, help="stamp of the first frame [s] (default 1e9)")
    parser.add_argument("--float", action="store_true", help="depth as 32FC1 metres instead of 16UC1 mm")
    parser.add_argument("--depth-topic", default="/camera/depth/image_raw")
    parser.add_argument("--color-topic", default="/camera/rgb/image_raw", help="empty: no colour")
    parser.add_argument("--no-color", dest="color_topic", action="store_const", const="", help="leave colour out")
    parser.add_argument("--frame-id", default="camera_depth_optical_frame")
    args = parser.parse_args(argv)
    if not args.rate > 0:
        parser.error("--rate must be positive")
    try:
        n = write_bag(args)
    except DatasetError as e:
        print(f"write_bag.py: {e}", file=sys.stderr)
        return 1
    print(f"{args.out}: {n} frames at {args.rate:g} Hz on {args.depth_topic}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
