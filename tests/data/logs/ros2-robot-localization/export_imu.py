#!/usr/bin/python3
"""Exports /imu/data of ../ros1-robot-localization/test2.bag as JSON, read by Debian's
python3-rosbag (an independent reader of the real ROS 1 recording): receive time and header stamp
in ns, frame_id, orientation, angular_velocity, linear_acceleration and the three covariances."""
import json
import sys

import rosbag

bag = rosbag.Bag(sys.argv[1])
out = []
for _, m, t in bag.read_messages(topics=["/imu/data"]):
    out.append({
        "time_ns": t.to_nsec(),
        "sec": m.header.stamp.secs, "nanosec": m.header.stamp.nsecs, "frame_id": m.header.frame_id,
        "orientation": [m.orientation.x, m.orientation.y, m.orientation.z, m.orientation.w],
        "orientation_covariance": list(m.orientation_covariance),
        "angular_velocity": [m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z],
        "angular_velocity_covariance": list(m.angular_velocity_covariance),
        "linear_acceleration": [m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z],
        "linear_acceleration_covariance": list(m.linear_acceleration_covariance),
    })
json.dump(out, open(sys.argv[2], "w"))
