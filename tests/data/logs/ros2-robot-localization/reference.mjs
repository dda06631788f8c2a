// Reference numbers of MCAP files read back by independent readers: @mcap/core's McapStreamReader
// (every record in file order: per topic the count and the first / last log time in file order)
// and, for sensor_msgs/msg/Imu and Temperature, @foxglove/rosmsg2-serialization's MessageReader
// (CDR, any encapsulation: header stamp, angular velocity, linear acceleration, temperature of the
// first and last message). Prints JSON keyed by the file names given.
import fs from "node:fs";
import { McapStreamReader } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";
import zstd from "@foxglove/wasm-zstd";
import lz4 from "@foxglove/wasm-lz4";  // decompress(data, size)

await zstd.isLoaded;
await lz4.isLoaded;
const out = {};
for (const file of process.argv.slice(2)) {
  const reader = new McapStreamReader({
    decompressHandlers: { zstd: (d, size) => zstd.decompress(d, Number(size)), lz4: (d, size) => lz4(d, Number(size)) },
  });
  reader.append(fs.readFileSync(file));
  const schemas = new Map(), channels = new Map(), topics = {};
  let record;
  while ((record = reader.nextRecord())) {
    if (record.type === "Schema") schemas.set(record.id, record);
    if (record.type === "Channel") channels.set(record.id, record);
    if (record.type !== "Message") continue;
    const channel = channels.get(record.channelId);
    const schema = schemas.get(channel.schemaId);
    const t = (topics[channel.topic] ??= { type: schema.name, count: 0 });
    t.count++;
    const value = { log_time: record.logTime.toString() };
    if (schema.name === "sensor_msgs/msg/Imu" || schema.name === "sensor_msgs/msg/Temperature") {
      t.reader ??= new MessageReader(parse(new TextDecoder().decode(schema.data), { ros2: true }));
      const m = t.reader.readMessage(record.data);
      value.stamp_ns = (BigInt(m.header.stamp.sec) * 1000000000n + BigInt(m.header.stamp.nanosec)).toString();
      if (m.angular_velocity) Object.assign(value, { angular_velocity: [m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z], linear_acceleration: [m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z] });
      else value.temperature = m.temperature;
    }
    if (t.count === 1) t.first = value;
    t.last = value;
  }
  for (const t of Object.values(topics)) delete t.reader;
  out[file.split("/").pop()] = { bytes: fs.statSync(file).size, topics };
}
console.log(JSON.stringify(out, null, 1));
