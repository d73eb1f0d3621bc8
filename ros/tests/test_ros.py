"""The ROS node, nodelet, launch files and bag script against a real master (ros/tests/rosharness.py).

ctest runs each test in a process of its own (ros_node_bag, ros_nodelet, ...), each with its own master.
Processes are stopped by PID with SIGTERM (roslaunch with SIGINT, which it passes on to its nodes).
Bags are played at 2 frames per second, slower than the node on the shared 2-core host, so that every
frame is segmented in order, as `clutterseg segment DIR` does: the labels must then be equal byte for byte.
"""
import json
import os
import signal
import subprocess
import sys
import time

import cv2
import numpy as np
import pytest

from rosharness import (BUILD_PACKAGE, DATA, NODE, Collector, Master, cli_labels, dataset_names, labels_of,
                        wait_until, write_bag)

sys.path.insert(0, os.path.join(BUILD_PACKAGE, "python"))

import rosbag  # noqa: E402
import rospy  # noqa: E402
from clutterseg_ros.msg import FrameStatistics, ObjectArray  # noqa: E402
from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from sensor_msgs.msg import CameraInfo, Image  # noqa: E402
from std_msgs.msg import String  # noqa: E402

RATE = 2.0            # frames per second in the test bags
START = 1e9           # stamp of a bag's first frame (write_bag.py's default)
OSD = os.path.join(DATA, "osd-kinect")
REALSENSE = os.path.join(DATA, "tabletop-realsense")


@pytest.fixture(scope="module")
def master(tmp_path_factory):
    m = Master(tmp_path_factory.mktemp("ros"))
    m.use_in_this_process()
    rospy.init_node("clutterseg_test", anonymous=True, disable_signals=True)
    yield m
    rospy.signal_shutdown("tests done")
    m.stop()


def start_node(master, name, depth_topic, params=None):
    if params is not None:
        rospy.set_param("/" + name, params)
    return master.start([NODE, f"__name:={name}", f"depth/image:={depth_topic}"], name + ".log")


def frame_index(stamp):
    return int(round((stamp.to_sec() - START) * RATE))


def play(master, bag, depth_topic, frames, delay=0):
    """rosbag play of the depth image and its camera_info, once the node has subscribed to both (and
    `delay` s more, for further subscribers to connect)."""
    info_topic = depth_topic.rsplit("/", 1)[0] + "/camera_info"
    player = master.start(["rosbag", "play", "--quiet", "--wait-for-subscribers", "--delay", str(delay), bag,
                           "--topics", depth_topic, info_topic], "rosbag-play.log")
    assert player.wait(timeout=frames / RATE + 60) == 0, player.log()


def segment_bag(master, name, bag, frames, start=None, params=None, depth_topic="/camera/depth/image_raw"):
    """Starts the node (or `start()`), plays the bag, returns its labels, statistics, objects and log."""
    labels = Collector(f"/{name}/labels", Image)
    stats = Collector(f"/{name}/statistics", FrameStatistics)
    objects = Collector(f"/{name}/objects", ObjectArray)
    node = start() if start else start_node(master, name, depth_topic, params)
    try:
        for c in (labels, stats, objects):
            c.wait_connected(details=node.log)
        play(master, bag, depth_topic, frames)
        for c in (labels, stats, objects):
            c.wait_for(frames, timeout=60, details=node.log)
        assert node.alive(), node.log()
    finally:
        code = node.stop()
        for c in (labels, stats, objects):
            c.close()
    if start is None:  # the node shuts down cleanly on SIGTERM
        assert code == 0, node.log()
    return labels.snapshot(), stats.snapshot(), objects.snapshot(), node.log()


def assert_same_labels(got, reference, names, log):
    """A label image arrived for every frame, in order, equal to the CLI's byte for byte."""
    assert [frame_index(m.header.stamp) for m in got] == list(range(len(names))), log
    for msg in got:
        name = names[frame_index(msg.header.stamp)]
        image = labels_of(msg)
        assert image.shape == reference[name].shape, name
        differ = int(np.count_nonzero(image != reference[name]))
        assert differ == 0, f"{name}: {differ} pixels differ from clutterseg segment"


def assert_every_frame_processed(stats, frames):
    last = stats[-1]
    assert (last.processed, last.dropped, last.rejected, last.failed) == (frames, 0, 0, 0), last
    assert all(s.segment_ms > 0 and s.latency_ms >= s.segment_ms for s in stats)
    assert stats[0].stage_names[-1] == "total"


def test_node_bag(master, tmp_path):
    """Bags of two real sets (16UC1 mm) and one in 32FC1 metres: labels equal `clutterseg segment`."""
    diagnostics = Collector("/diagnostics", DiagnosticArray)
    for dataset, options in ((OSD, ()), (REALSENSE, ()), (OSD, ("--float",))):
        names = dataset_names(dataset)
        reference = cli_labels(dataset, tmp_path / ("cli-" + os.path.basename(dataset)))
        bag = write_bag(dataset, tmp_path / "frames.bag", "--rate", str(RATE), *options)
        name = "clutterseg_" + os.path.basename(dataset).replace("-", "_") + ("_float" if options else "")
        labels, stats, objects, log = segment_bag(master, name, bag, len(names))
        assert_same_labels(labels, reference, names, log)
        assert_every_frame_processed(stats, len(names))
        # One ObjectArray per frame, listing exactly the ids of its label image.
        for msg, obj in zip(labels, objects):
            assert obj.header.stamp == msg.header.stamp
            ids = sorted(int(i) for i in np.unique(labels_of(msg)) if i != 0)
            assert [o.id for o in obj.objects] == ids
            assert all(o.pixel_count > 0 and o.box_size.x >= o.box_size.y >= 0 for o in obj.objects)
        assert any(o.has_support_plane for o in objects)
    # The node reported its counters on /diagnostics.
    wait_until("a clutterseg status on /diagnostics", lambda: any(
        "segmentation" in s.name for m in diagnostics.snapshot() for s in m.status), timeout=10)
    diagnostics.close()


def test_node_params(master, tmp_path):
    """Private parameters reach the segmenter (labels equal the CLI with the same config) and are echoed;
    unknown names and wrong types stop the node with a log line naming the parameter."""
    params = {"graph": {"theta_c": 0.3}, "support": {"objects_only": True}, "seed": 7}
    config = tmp_path / "config.json"
    config.write_text(json.dumps(params))
    names = dataset_names(OSD)
    reference = cli_labels(OSD, tmp_path / "cli-config", "--config", str(config))
    default = cli_labels(OSD, tmp_path / "cli-default")
    assert any(not np.array_equal(reference[n], default[n]) for n in names), "the parameters change nothing"

    echoed = Collector("/clutterseg_params/params", String)
    bag = write_bag(OSD, tmp_path / "osd.bag", "--rate", str(RATE))
    labels, stats, _, log = segment_bag(master, "clutterseg_params", bag, len(names), params=params)
    assert_same_labels(labels, reference, names, log)
    assert_every_frame_processed(stats, len(names))
    echoed.wait_for(1, timeout=10)
    effective = json.loads(echoed.snapshot()[0].data)
    assert effective["graph"]["theta_c"] == 0.3 and effective["support"]["objects_only"] is True
    assert effective["seed"] == 7
    echoed.close()

    for name, bad, expected in (
            ("bad_name", {"graph": {"theta_x": 0.7}}, ["unknown parameter 'graph.theta_x'", "/bad_name/graph/theta_x"]),
            ("bad_group", {"theta_c": 0.7}, ["unknown parameter 'theta_c'", "/bad_group/theta_c"]),
            ("bad_type", {"graph": {"theta_c": "high"}}, ["ROS parameters in /bad_type"])):
        node = start_node(master, name, "/unused/depth/image_raw", bad)
        code = node.wait(timeout=30)
        log = node.log()
        assert code != 0, log
        assert "FATAL" in log, log
        for text in expected:
            assert text in log, log


def test_node_target_frame(master, tmp_path):
    """With ~target_frame, objects and the support plane come in that frame through tf2 (compared with a
    node in the camera frame on the same frames); without a transform they stay in the camera frame and
    the node says why."""
    from geometry_msgs.msg import TransformStamped
    from tf2_msgs.msg import TFMessage
    # The camera 1 m above base_link, looking along its x axis (optical frame: z forward, x right, y down).
    camera = TransformStamped()
    camera.header.frame_id, camera.child_frame_id = "base_link", "camera_depth_optical_frame"
    camera.transform.translation.x, camera.transform.translation.z = 0.1, 1.0
    q = camera.transform.rotation
    q.x, q.y, q.z, q.w = -0.5, 0.5, -0.5, 0.5
    rotation = np.array([[0, 0, 1], [-1, 0, 0], [0, -1, 0]], float)  # the same rotation as a matrix
    translation = np.array([0.1, 0.0, 1.0])
    tf_static = rospy.Publisher("/tf_static", TFMessage, queue_size=1, latch=True)
    tf_static.publish(TFMessage(transforms=[camera]))

    names = dataset_names(OSD)
    bag = write_bag(OSD, tmp_path / "osd.bag", "--rate", str(RATE))
    # Three nodes on the same frames: one thread each, so that together they keep up on two cores.
    runs = {"in_camera": {"threads": 1}, "in_base": {"target_frame": "base_link", "threads": 1},
            "in_nowhere": {"target_frame": "nowhere", "tf_timeout": 0.01, "threads": 1}}
    objects = {name: Collector(f"/{name}/objects", ObjectArray) for name in runs}
    nodes = {name: start_node(master, name, "/camera/depth/image_raw", params) for name, params in runs.items()}
    try:
        for name in runs:
            objects[name].wait_connected(details=nodes[name].log)
        play(master, bag, "/camera/depth/image_raw", len(names), delay=1)
        for name in runs:
            objects[name].wait_for(len(names), timeout=60, details=nodes[name].log)
    finally:
        for name in runs:
            nodes[name].stop()
            objects[name].close()
        tf_static.unregister()
    for in_camera, in_base, in_nowhere in zip(*(objects[name].snapshot() for name in runs)):
        assert in_camera.header.stamp == in_base.header.stamp == in_nowhere.header.stamp
        assert (in_camera.header.frame_id, in_base.header.frame_id, in_nowhere.header.frame_id) == (
            "camera_depth_optical_frame", "base_link", "camera_depth_optical_frame")
        assert [o.id for o in in_camera.objects] == [o.id for o in in_base.objects]
        for a, b in zip(in_camera.objects, in_base.objects):
            expected = rotation @ np.array([a.centroid.x, a.centroid.y, a.centroid.z]) + translation
            assert np.allclose([b.centroid.x, b.centroid.y, b.centroid.z], expected, atol=1e-5)
            assert (a.box_size.x, a.box_size.y, a.box_size.z) == (b.box_size.x, b.box_size.y, b.box_size.z)
        if in_camera.has_support_plane:  # the plane's normal turns with the camera; its points stay on it
            n = rotation @ np.array(in_camera.support_plane[:3])
            assert np.allclose(in_base.support_plane[:3], n, atol=1e-6)
            on_plane = -in_camera.support_plane[3] * np.array(in_camera.support_plane[:3])
            assert abs(np.dot(in_base.support_plane[:3], rotation @ on_plane + translation) + in_base.support_plane[3]) < 1e-5
    assert "no transform from 'camera_depth_optical_frame' to 'nowhere'" in nodes["in_nowhere"].log()


def publish_frame(image_pub, info_pub, depth, encoding, info_size, stamp, intrinsics=(525.0, 525.0, 319.5, 239.5)):
    fx, fy, cx, cy = intrinsics
    header = rospy.Header(stamp=stamp, frame_id="camera_depth_optical_frame")
    image = Image(header=header, height=depth.shape[0], width=depth.shape[1], encoding=encoding, is_bigendian=0,
                  step=depth.strides[0], data=np.ascontiguousarray(depth).tobytes())
    info = CameraInfo(header=header, width=info_size[0], height=info_size[1], distortion_model="plumb_bob",
                      D=[0.0] * 5, K=[fx, 0, cx, 0, fy, cy, 0, 0, 1], R=[1, 0, 0, 0, 1, 0, 0, 0, 1],
                      P=[fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0])
    info_pub.publish(info)
    image_pub.publish(image)


def test_node_malformed(master, tmp_path):
    """Wrong encoding, a size that does not match CameraInfo and an empty depth image are logged and
    skipped (a repeat within 5 s only counted); the node goes on, and the next good frame is segmented as
    if they had never come."""
    name, topic = "clutterseg_malformed", "/malformed/depth/image_raw"
    image_pub = rospy.Publisher(topic, Image, queue_size=10)
    info_pub = rospy.Publisher("/malformed/depth/camera_info", CameraInfo, queue_size=10)
    labels = Collector(f"/{name}/labels", Image)
    stats = Collector(f"/{name}/statistics", FrameStatistics)
    node = start_node(master, name, topic)
    try:
        labels.wait_connected(details=node.log)
        stats.wait_connected(details=node.log)
        wait_until("the node's depth subscriptions", lambda: image_pub.get_num_connections() > 0
                   and info_pub.get_num_connections() > 0, timeout=20)
        good = cv2.imread(os.path.join(OSD, "depth", "learn6.png"), cv2.IMREAD_UNCHANGED)
        colour = np.zeros((480, 640, 3), np.uint8)
        bad_frames = [
            (colour, "rgb8", (640, 480), "encoding 'rgb8', expected 16UC1 (mm) or 32FC1 (m)"),
            (good, "16UC1", (320, 240), "image is 640x480 but its CameraInfo is 320x240"),
            (np.zeros_like(good), "16UC1", (640, 480), "depth image has no valid measurement"),
        ]
        for i, (depth, encoding, size, expected) in enumerate(bad_frames):
            publish_frame(image_pub, info_pub, depth, encoding, size, rospy.Time(100 + i))
            wait_until(f"log line '{expected}'", lambda: expected in node.log(), timeout=20)
            assert node.alive(), node.log()
        # The same problem again within 5 s: counted, not logged again.
        for i in range(2):
            time.sleep(0.3)  # ROS's own queue of one may drop a frame that follows another too closely
            publish_frame(image_pub, info_pub, good, "16UC1", (320, 240), rospy.Time(105 + i))
        time.sleep(0.3)
        publish_frame(image_pub, info_pub, good, "16UC1", (640, 480), rospy.Time(110))
        labels.wait_for(1, timeout=30)
        stats.wait_for(1, timeout=30)
        assert node.alive(), node.log()
    finally:
        node.stop()
        labels.close()
        stats.close()
        image_pub.unregister()
        info_pub.unregister()
    last = stats.snapshot()[-1]
    assert (last.failed, last.processed) == (1, 1) and last.received == last.rejected + 2, last
    assert last.rejected >= 3, last  # at least one repeat came, and was not logged again
    lines = [line for line in node.log().splitlines() if "frame skipped" in line]
    assert len(lines) == 2 and all("ERROR" in line for line in lines), lines
    # The bad frames never entered the temporal window: the CLI on that one file gives the same labels.
    single = tmp_path / "cli-single"
    subprocess.run([os.environ["CLUTTERSEG_CLI"], "segment", os.path.join(OSD, "depth", "learn6.png"), "--out",
                    str(single)], check=True, timeout=120, stdout=subprocess.DEVNULL)
    reference = cv2.imread(str(single / "label" / "learn6.png"), cv2.IMREAD_UNCHANGED)
    assert np.array_equal(labels_of(labels.snapshot()[0]), reference)


def test_nodelet(master, tmp_path):
    """The nodelet loads into a nodelet manager and gives the same labels as the CLI."""
    names = dataset_names(OSD)
    reference = cli_labels(OSD, tmp_path / "cli")
    bag = write_bag(OSD, tmp_path / "osd.bag", "--rate", str(RATE))
    manager = master.start(["/usr/lib/nodelet/nodelet", "manager", "__name:=clutterseg_manager"], "manager.log")
    try:
        def load():
            return master.start(["/usr/lib/nodelet/nodelet", "load", "clutterseg_ros/SegmentationNodelet",
                                 "clutterseg_manager", "__name:=clutterseg_nodelet",
                                 "depth/image:=/camera/depth/image_raw"], "nodelet-load.log")
        labels, stats, _, log = segment_bag(master, "clutterseg_nodelet", bag, len(names), start=load)
        assert_same_labels(labels, reference, names, log + manager.log())
        assert_every_frame_processed(stats, len(names))
        # A refused parameter: the nodelet is not loaded, the manager says why and goes on.
        rospy.set_param("/bad_nodelet", {"graph": {"theta_x": 0.5}})
        bad = master.start(["/usr/lib/nodelet/nodelet", "load", "clutterseg_ros/SegmentationNodelet",
                            "clutterseg_manager", "__name:=bad_nodelet"], "bad-nodelet.log")
        assert bad.wait(timeout=30) != 0, bad.log()
        wait_until("the manager's log line", lambda: "(ROS parameter /bad_nodelet/graph/theta_x)" in manager.log(),
                   timeout=10, details=manager.log)
        assert manager.alive(), manager.log()
    finally:
        manager.stop()


def test_launch(master, tmp_path):
    """bag.launch plays a bag into the node with a parameter file; camera.launch picks each driver's
    topic, or loads the nodelet into a manager."""
    launch_dir = os.path.join(BUILD_PACKAGE, "launch")
    for driver, topic in (("openni2", "/camera/depth/image_raw"), ("realsense2", "/camera/depth/image_rect_raw")):
        args = subprocess.run(["roslaunch", "--args", "clutterseg", os.path.join(launch_dir, "camera.launch"),
                               f"driver:={driver}"], env=master.env, capture_output=True, text=True, timeout=60)
        assert args.returncode == 0, args.stderr
        assert f"depth/image:={topic}" in args.stdout and "clutterseg_node" in args.stdout, args.stdout
    in_manager = subprocess.run(["roslaunch", "--args", "clutterseg", os.path.join(launch_dir, "camera.launch"),
                                 "manager:=/camera/camera_nodelet_manager"], env=master.env, capture_output=True,
                                text=True, timeout=60)
    assert "load clutterseg_ros/SegmentationNodelet /camera/camera_nodelet_manager" in in_manager.stdout, in_manager

    # A parameter file as `clutterseg --dump-config` writes it (JSON is YAML), with two values changed.
    dumped = subprocess.run([os.environ["CLUTTERSEG_CLI"], "--dump-config"], check=True, capture_output=True,
                            text=True, timeout=60).stdout
    config = json.loads(dumped)
    config["graph"]["theta_c"], config["support"]["objects_only"] = 0.4, True
    config_path = tmp_path / "params.json"
    config_path.write_text(json.dumps(config, indent=1))
    names = dataset_names(OSD)
    reference = cli_labels(OSD, tmp_path / "cli", "--config", str(config_path))
    bag = write_bag(OSD, tmp_path / "osd.bag", "--rate", str(RATE))
    labels = Collector("/launched/labels", Image)
    launch = master.start(["roslaunch", os.path.join(launch_dir, "bag.launch"), f"bag:={bag}", "name:=launched",
                           f"params:={config_path}"], "roslaunch.log")
    try:
        labels.wait_for(len(names), timeout=len(names) / RATE + 60, details=launch.log)
        assert launch.alive(), launch.log()
    finally:
        launch.stop(signal.SIGINT, timeout=20)
        labels.close()
    assert_same_labels(labels.snapshot(), reference, names, launch.log())


def test_write_bag(tmp_path):
    """write_bag.py: depth as the PNGs' bytes (or metres), CameraInfo from camera.json, colour, stamps;
    a folder without camera.json is refused with a one-line error and leaves no bag."""
    bag_path = write_bag(OSD, tmp_path / "osd.bag", "--rate", "10")
    names = dataset_names(OSD)
    camera = json.load(open(os.path.join(OSD, "camera.json")))
    seen = {}
    with rosbag.Bag(bag_path) as bag:
        for topic, msg, t in bag.read_messages():
            seen.setdefault(topic, []).append((msg, t))
    assert sorted(seen) == ["/camera/depth/camera_info", "/camera/depth/image_raw", "/camera/rgb/camera_info",
                            "/camera/rgb/image_raw"]
    assert all(len(v) == len(names) for v in seen.values())
    for i, ((depth, t), (info, _), (color, _)) in enumerate(zip(seen["/camera/depth/image_raw"],
                                                                  seen["/camera/depth/camera_info"],
                                                                  seen["/camera/rgb/image_raw"])):
        assert depth.header.stamp == info.header.stamp == color.header.stamp == t
        assert abs(t.to_sec() - (START + i / 10.0)) < 1e-6
        png = cv2.imread(os.path.join(OSD, "depth", names[i] + ".png"), cv2.IMREAD_UNCHANGED)
        assert depth.encoding == "16UC1" and bytes(depth.data) == png.tobytes()
        assert list(info.K) == [camera["fx"], 0, camera["cx"], 0, camera["fy"], camera["cy"], 0, 0, 1]
        assert (info.width, info.height) == (640, 480)
        assert color.encoding == "bgr8" and (color.width, color.height) == (640, 480)

    float_path = write_bag(OSD, tmp_path / "osd-float.bag", "--float", "--no-color")
    with rosbag.Bag(float_path) as bag:
        assert sorted(bag.get_type_and_topic_info().topics) == ["/camera/depth/camera_info", "/camera/depth/image_raw"]
        msg = next(m for _, m, _ in bag.read_messages(topics=["/camera/depth/image_raw"]))
    png = cv2.imread(os.path.join(OSD, "depth", names[0] + ".png"), cv2.IMREAD_UNCHANGED)
    metres = np.frombuffer(msg.data, "<f4").reshape(480, 640)
    assert msg.encoding == "32FC1" and np.array_equal(metres, png.astype(np.float32) * np.float32(0.001))

    broken = tmp_path / "broken"
    (broken / "depth").mkdir(parents=True)
    result = subprocess.run(["/usr/bin/python3", os.path.join(BUILD_PACKAGE, "scripts", "write_bag.py"), str(broken),
                             str(tmp_path / "broken.bag")], capture_output=True, text=True, timeout=60)
    assert result.returncode == 1
    assert result.stderr.count("\n") == 1 and "camera.json" in result.stderr, result.stderr
    assert not os.path.exists(tmp_path / "broken.bag") and not os.path.exists(tmp_path / "broken.bag.tmp")
