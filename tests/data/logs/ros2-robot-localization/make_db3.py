#!/usr/bin/python3
"""Writes the rosbag2 sqlite3 fixtures from cdr_messages.json (CDR bytes written by
@foxglove/rosmsg2-serialization, make_fixtures.mjs) in rosbag2's sqlite3 schema (topics, messages;
as rosbag2_storage_default_plugins creates them), each a directory with its metadata.yaml:
  imu_db3/                   500 Imu + 50 Temperature messages
  imu_db3_zstd_messages/     the first 100 Imu messages, each zstd-compressed (compression_mode MESSAGE)"""
import base64
import json
import os
import sqlite3


def write(name, topics, compression=""):
    os.makedirs(name, exist_ok=True)
    path = f"{name}/{name}_0.db3"
    if os.path.exists(path):
        os.remove(path)
    db = sqlite3.connect(path)
    db.execute("CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
               "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL)")
    db.execute("CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, "
               "timestamp INTEGER NOT NULL, data BLOB NOT NULL)")
    db.execute("CREATE INDEX timestamp_idx ON messages (timestamp ASC)")
    rows = []
    for topic_id, (topic, type_, msgs) in enumerate(topics, start=1):
        db.execute("INSERT INTO topics VALUES (?, ?, ?, 'cdr', '')", (topic_id, topic, type_))
        rows += [(topic_id, m["time_ns"], base64.b64decode(m["data"])) for m in msgs]
    rows.sort(key=lambda r: (r[1], r[0]))  # receive order, as a recorder inserts them
    db.executemany("INSERT INTO messages(topic_id, timestamp, data) VALUES (?, ?, ?)", rows)
    db.commit()
    db.execute("VACUUM")
    db.close()
    start = min(m["time_ns"] for _, _, msgs in topics for m in msgs)
    end = max(m["time_ns"] for _, _, msgs in topics for m in msgs)
    listed = "".join(f"""
    - topic_metadata:
        name: {topic}
        type: {type_}
        serialization_format: cdr
        offered_qos_profiles: ""
      message_count: {len(msgs)}""" for topic, type_, msgs in topics)
    with open(f"{name}/metadata.yaml", "w") as f:
        f.write(f"""rosbag2_bagfile_information:
  version: 5
  storage_identifier: sqlite3
  relative_file_paths:
    - {name}_0.db3
  duration:
    nanoseconds: {end - start}
  starting_time:
    nanoseconds_since_epoch: {start}
  message_count: {sum(len(msgs) for _, _, msgs in topics)}
  topics_with_message_count:{listed}
  compression_format: "{compression}"
  compression_mode: "{'MESSAGE' if compression else ''}"
""")


messages = json.load(open("cdr_messages.json"))
write("imu_db3", [("/imu/data", "sensor_msgs/msg/Imu", messages["imu"]),
                  ("/imu/temperature", "sensor_msgs/msg/Temperature", messages["temperature"])])
write("imu_db3_zstd_messages", [("/imu/data", "sensor_msgs/msg/Imu", messages["imu_zstd"])], "zstd")
