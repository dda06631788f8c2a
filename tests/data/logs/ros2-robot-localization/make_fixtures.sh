#!/usr/bin/env bash
# Regenerates the ROS 2 fixtures of this folder and the reference_*.json of this folder and of
# ../ros2-rosbag2 (see README.md). Needs Debian's
# python3-rosbag, python3-sensor-msgs and sqlite3, and node + npm (the npm packages pinned in
# package-lock.json are installed into ./node_modules, which is not committed).
set -euo pipefail
cd "$(dirname "$0")"
npm ci --no-audit --no-fund --silent
/usr/bin/python3 export_imu.py ../ros1-robot-localization/test2.bag imu.json
node make_fixtures.mjs imu.json
/usr/bin/python3 make_db3.py
node reference.mjs *.mcap > reference_mcap.json
node reference.mjs ../ros2-rosbag2/*/*.mcap > ../ros2-rosbag2/reference_mcap.json
counts="SELECT t.name, t.type, COUNT(m.id) AS count, MIN(m.timestamp) AS first_ns, MAX(m.timestamp) AS last_ns
  FROM topics t LEFT JOIN messages m ON m.topic_id = t.id GROUP BY t.name ORDER BY t.name"
sqlite3 -json imu_db3/imu_db3_0.db3 "$counts" > reference_db3.json
/usr/bin/python3 -c 'import json, os, subprocess, sys
print(json.dumps({os.path.basename(db): json.loads(subprocess.check_output(["sqlite3", "-json", db, sys.argv[1]]))
                  for db in sys.argv[2:]}, indent=1))' "$counts" ../ros2-rosbag2/*/*.db3 > ../ros2-rosbag2/reference_db3.json
node make_fuzz_seeds.mjs
/usr/bin/python3 - <<'PY'
# ROS 1 seeds of fuzz_ros_messages (mode bit 2): the first Imu of test2.bag as python3-rosbag
# serializes it, and a std_msgs/Float64.
from io import BytesIO
import rosbag
from std_msgs.msg import Float64
out = "../../../fuzz/corpus/ros_messages/"
_, m, _ = next(rosbag.Bag("../ros1-robot-localization/test2.bag").read_messages(topics=["/imu/data"]))
for name, mode, msg in (("imu_ros1", 4, m), ("float64_ros1", 7, Float64(21.5))):
    buf = BytesIO()
    msg.serialize(buf)
    open(out + name, "wb").write(bytes([mode]) + buf.getvalue())
PY
rm -rf node_modules imu.json cdr_messages.json
