#!/usr/bin/python3
"""Writes the rosbag2 sqlite3 fixture imu_db3/ (metadata.yaml and imu_db3_0.db3) from
cdr_messages.json (CDR bytes written by @foxglove/rosmsg2-serialization, make_fixtures.mjs) in
rosbag2's sqlite3 schema (topics, messages; as rosbag2_storage_default_plugins creates them)."""
import base64
import json
import os
import sqlite3

os.makedirs("imu_db3", exist_ok=True)
path = "imu_db3/imu_db3_0.db3"
if os.path.exists(path):
    os.remove(path)
messages = json.load(open("cdr_messages.json"))
db = sqlite3.connect(path)
db.execute("CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
           "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL)")
db.execute("CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, "
           "timestamp INTEGER NOT NULL, data BLOB NOT NULL)")
db.execute("CREATE INDEX timestamp_idx ON messages (timestamp ASC)")
db.execute("INSERT INTO topics VALUES (1, '/imu/data', 'sensor_msgs/msg/Imu', 'cdr', '')")
db.execute("INSERT INTO topics VALUES (2, '/imu/temperature', 'sensor_msgs/msg/Temperature', 'cdr', '')")
rows = [(1, m["time_ns"], base64.b64decode(m["data"])) for m in messages["imu"]]
rows += [(2, m["time_ns"], base64.b64decode(m["data"])) for m in messages["temperature"]]
rows.sort(key=lambda r: (r[1], r[0]))  # receive order, as a recorder inserts them
db.executemany("INSERT INTO messages(topic_id, timestamp, data) VALUES (?, ?, ?)", rows)
db.commit()
db.execute("VACUUM")
db.close()
imu, temperature = messages["imu"], messages["temperature"]
start = min(imu[0]["time_ns"], temperature[0]["time_ns"])
end = max(imu[-1]["time_ns"], temperature[-1]["time_ns"])
with open("imu_db3/metadata.yaml", "w") as f:
    f.write(f"""rosbag2_bagfile_information:
  version: 5
  storage_identifier: sqlite3
  relative_file_paths:
    - imu_db3_0.db3
  duration:
    nanoseconds: {end - start}
  starting_time:
    nanoseconds_since_epoch: {start}
  message_count: {len(imu) + len(temperature)}
  topics_with_message_count:
    - topic_metadata:
        name: /imu/data
        type: sensor_msgs/msg/Imu
        serialization_format: cdr
        offered_qos_profiles: ""
      message_count: {len(imu)}
    - topic_metadata:
        name: /imu/temperature
        type: sensor_msgs/msg/Temperature
        serialization_format: cdr
        offered_qos_profiles: ""
      message_count: {len(temperature)}
  compression_format: ""
  compression_mode: ""
""")
