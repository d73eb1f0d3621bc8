"""Shared fixtures of the Python tests. ctest sets the paths (python/CMakeLists.txt); run by hand from the
repository: PYTHONPATH=build/python /usr/bin/python3 -m pytest python/tests"""
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import clutterseg

SOURCE_DIR = Path(os.environ.get("CLUTTERSEG_SOURCE_DIR", Path(__file__).resolve().parents[2]))
BUILD_DIR = Path(os.environ.get("CLUTTERSEG_BUILD_DIR", SOURCE_DIR / "build"))
DATA_DIR = Path(os.environ.get("CLUTTERSEG_DATA_DIR", SOURCE_DIR.parent / "shared" / "data" / "dev"))
CLI = Path(os.environ.get("CLUTTERSEG_CLI", BUILD_DIR / "clutterseg"))

# The dev sets with depth PNGs (pcl-organized holds PCDs only).
DEV_SETS = ["osd-kinect", "tabletop-realsense", "ycbv-0000", "ycbv-0003"]


def run_cli(*args, timeout=300, check=True):
    """Runs the clutterseg tool; returns the CompletedProcess (stdout, stderr as text)."""
    run = subprocess.run([str(CLI), *map(str, args)], capture_output=True, text=True, timeout=timeout)
    if check and run.returncode != 0:
        raise AssertionError(f"clutterseg {' '.join(map(str, args))} exited {run.returncode}: {run.stderr}")
    return run


@pytest.fixture(scope="session")
def example_frame():
    """The bundled OSD frame: uint16 mm depth, 640x480, Kinect v1 intrinsics."""
    return clutterseg.Dataset(SOURCE_DIR / "examples" / "osd-test50")["test50"]


def labels_equal(a, b):
    return a.shape == b.shape and np.array_equal(a, b)
