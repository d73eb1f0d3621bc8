"""What the ROS tests share: a master of their own, processes stopped by PID, bounded waits, the CLI.

Each test process starts `rosmaster --core` on a free 127.0.0.1 port (ROS_HOME and ROS_LOG_DIR in a temp
folder) and stops it with SIGTERM by its PID. Every wait has a bound and fails with what it waited for.
Paths come from the environment ctest sets (ros/tests/CMakeLists.txt).
"""
import contextlib
import os
import signal
import socket
import subprocess
import threading
import time
import xmlrpc.client

import cv2
import numpy as np

BUILD_PACKAGE = os.environ.get("CLUTTERSEG_ROS_PACKAGE", "")  # <build>/ros/clutterseg_ros
CLI = os.environ.get("CLUTTERSEG_CLI", "")
DATA = os.environ.get("CLUTTERSEG_DATA", "")
NODE = os.path.join(BUILD_PACKAGE, "bin", "clutterseg_node")
WRITE_BAG = os.path.join(BUILD_PACKAGE, "scripts", "write_bag.py")


def wait_until(what, condition, timeout, details=None):
    """Polls condition() until it is true; fails naming `what` (and details(), e.g. a log) after `timeout` s."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            more = ": " + details() if details else ""
            raise AssertionError(f"timed out after {timeout:g} s waiting for {what}{more}")
        time.sleep(0.02)


def free_port():
    with contextlib.closing(socket.socket(socket.AF_INET, socket.SOCK_STREAM)) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _default_sigint():
    # Background processes of a non-interactive shell ignore SIGINT; a node must stop on it.
    signal.signal(signal.SIGINT, signal.SIG_DFL)


class Process:
    """A child process with its output in a log file; stopped by its PID, never by name."""

    def __init__(self, cmd, log_path, env=None):
        self.cmd = cmd
        self.log_path = log_path
        self._log = open(log_path, "wb")
        self.proc = subprocess.Popen(cmd, stdout=self._log, stderr=subprocess.STDOUT, env=env,
                                     preexec_fn=_default_sigint)

    def log(self):
        with open(self.log_path, "rb") as f:
            return f.read().decode(errors="replace")

    def alive(self):
        return self.proc.poll() is None

    def wait(self, timeout):
        try:
            return self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            raise AssertionError(f"{self.cmd[0]} still running after {timeout:g} s; log:\n{self.log()}")

    def stop(self, sig=signal.SIGTERM, timeout=10):
        """Asks the process to stop with `sig`; SIGKILL after `timeout` s. Returns its exit code."""
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=10)
        self._log.close()
        return self.proc.returncode


class Master:
    """rosmaster on a free local port, with the environment every ROS process of the test uses."""

    def __init__(self, tmp):
        self.tmp = str(tmp)
        self.env = dict(os.environ)
        self.env.update({
            "ROS_IP": "127.0.0.1",
            "ROS_HOME": os.path.join(self.tmp, "ros_home"),
            "ROS_LOG_DIR": os.path.join(self.tmp, "ros_log"),
            "ROSCONSOLE_STDOUT_LINE_BUFFERED": "1",
            # As the launch files do: spinning OpenMP threads make the segmenter several times slower
            # when the cores are shared (docs/ROS.md), and the tests share two cores with everything.
            "OMP_WAIT_POLICY": "passive",
            "ROS_PACKAGE_PATH": os.path.dirname(BUILD_PACKAGE),
            "PYTHONPATH": os.pathsep.join(filter(None, [os.path.join(BUILD_PACKAGE, "python"),
                                                        os.environ.get("PYTHONPATH", "")])),
        })
        self.process = None
        for _attempt in range(3):  # the port may be taken between free_port() and rosmaster's bind
            self.port = free_port()
            self.uri = f"http://127.0.0.1:{self.port}"
            self.env["ROS_MASTER_URI"] = self.uri
            self.process = Process(["rosmaster", "--core", "-p", str(self.port)],
                                   os.path.join(self.tmp, f"rosmaster-{self.port}.log"), self.env)
            if self._wait_ready(timeout=15):
                return
            self.process.stop(signal.SIGTERM)
        raise AssertionError(f"rosmaster did not start; log:\n{self.process.log()}")

    def _wait_ready(self, timeout):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and self.process.alive():
            try:
                code, _, _ = xmlrpc.client.ServerProxy(self.uri).getPid("/clutterseg_test")
                if code == 1:
                    return True
            except OSError:
                pass
            time.sleep(0.05)
        return False

    def use_in_this_process(self):
        os.environ.update(self.env)

    def start(self, cmd, log_name):
        return Process(cmd, os.path.join(self.tmp, log_name), self.env)

    def stop(self):
        return self.process.stop(signal.SIGTERM)


class Collector:
    """Keeps every message of a topic (rospy), in arrival order."""

    def __init__(self, topic, msg_type):
        import rospy
        self.messages = []
        self._lock = threading.Lock()
        self.subscriber = rospy.Subscriber(topic, msg_type, self._keep, queue_size=1000)

    def _keep(self, msg):
        with self._lock:
            self.messages.append(msg)

    def count(self):
        with self._lock:
            return len(self.messages)

    def snapshot(self):
        with self._lock:
            return list(self.messages)

    def wait_connected(self, timeout=20, details=None):
        wait_until(f"a publisher on {self.subscriber.resolved_name}",
                   lambda: self.subscriber.get_num_connections() > 0, timeout, details)

    def wait_for(self, n, timeout, details=None):
        wait_until(f"{n} messages on {self.subscriber.resolved_name}", lambda: self.count() >= n, timeout,
                   lambda: f"{self.count()} arrived" + ("; " + details() if details else ""))

    def close(self):
        self.subscriber.unregister()


def labels_of(msg):
    """uint16 label image of a 16UC1 Image message."""
    assert msg.encoding == "16UC1", msg.encoding
    assert msg.step == msg.width * 2 and not msg.is_bigendian
    return np.frombuffer(msg.data, dtype="<u2").reshape(msg.height, msg.width)


def dataset_names(dataset):
    return sorted(f[:-4] for f in os.listdir(os.path.join(dataset, "depth")) if f.endswith(".png"))


def cli_labels(dataset, out, *options):
    """`clutterseg segment DATASET` (a stream, in name order): {frame name: uint16 label image}."""
    subprocess.run([CLI, "segment", dataset, "--out", str(out), *options], check=True, timeout=300,
                   stdout=subprocess.DEVNULL)
    return {n: cv2.imread(os.path.join(str(out), "label", n + ".png"), cv2.IMREAD_UNCHANGED)
            for n in dataset_names(dataset)}


def write_bag(dataset, bag, *options):
    subprocess.run(["/usr/bin/python3", WRITE_BAG, dataset, str(bag), *options], check=True, timeout=120,
                   stdout=subprocess.DEVNULL)
    return str(bag)
