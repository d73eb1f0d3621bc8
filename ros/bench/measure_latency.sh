#!/usr/bin/env bash
# End-to-end latency of 640x480 frames through ROS, and the input rate at which frames start to drop
# (docs/ROS.md). Starts a master on a free local port and the node, runs clutterseg_ros_latency, stops
# both by PID.
#   bash ros/bench/measure_latency.sh [DATASET] [RATES] [SECONDS_PER_RATE] [NODE_ARGS...]
# e.g. bash ros/bench/measure_latency.sh ../shared/data/dev/tabletop-realsense 5,10,20 10 _threads:=1
set -euo pipefail
cd "$(dirname "$0")/../.."
PKG=${BUILD:-build}/ros/clutterseg_ros
DATASET=${1:-../shared/data/dev/tabletop-realsense}
RATES=${2:-5,10,20,30,40,50,60}
DURATION=${3:-10}
shift $(( $# < 3 ? $# : 3 ))  # the rest: node arguments (private parameters such as _threads:=1)
tmp=$(mktemp -d)
port=$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI=http://127.0.0.1:$port ROS_IP=127.0.0.1 ROS_HOME=$tmp ROS_LOG_DIR=$tmp ROSCONSOLE_STDOUT_LINE_BUFFERED=1
master="" node=""
cleanup() {
  # Background jobs of a script ignore SIGINT: stop both with SIGTERM, by PID.
  [ -n "$node" ] && kill -TERM "$node" 2>/dev/null || true
  [ -n "$master" ] && kill -TERM "$master" 2>/dev/null || true
  wait 2>/dev/null || true
  rm -rf "$tmp"
}
trap cleanup EXIT
rosmaster --core -p "$port" >"$tmp/master.log" 2>&1 &
master=$!
for _ in $(seq 100); do
  /usr/bin/python3 -c "import xmlrpc.client as x; x.ServerProxy('$ROS_MASTER_URI').getPid('/m')" 2>/dev/null && break
  sleep 0.1
done
"$PKG/bin/clutterseg_node" __name:=clutterseg depth/image:=/camera/depth/image_raw "$@" >"$tmp/node.log" 2>&1 &
node=$!
echo "$(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg); $DATASET; node arguments: $*"
"$PKG/bin/clutterseg_ros_latency" "$DATASET" --node /clutterseg --depth /camera/depth/image_raw --rates "$RATES" --seconds "$DURATION"
