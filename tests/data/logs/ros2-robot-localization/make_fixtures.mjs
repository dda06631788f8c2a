// Writes the ROS 2 fixtures of this folder from imu.json (export_imu.py) with third-party writers:
// @mcap/core's McapWriter (chunking, summary; chunks compressed by @foxglove/wasm-zstd and lz4js),
// @foxglove/rosmsg2-serialization's MessageWriter (CDR little endian, from the schema text) and
// @foxglove/cdr's CdrWriter (big endian and XCDR2 variants). Also writes cdr_messages.json (the
// serialized messages, base64; the first 100 IMU messages also zstd-compressed) for make_db3.py.
import fs from "node:fs";
import { McapWriter } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageWriter } from "@foxglove/rosmsg2-serialization";
import { CdrWriter, EncapsulationKind } from "@foxglove/cdr";
import zstd from "@foxglove/wasm-zstd";
import lz4 from "lz4js";
import * as schemas from "./schemas.mjs";

await zstd.isLoaded;
const imu = JSON.parse(fs.readFileSync(process.argv[2], "utf8"));
const imuWriter = new MessageWriter(parse(schemas.imu, { ros2: true }));
const temperatureWriter = new MessageWriter(parse(schemas.temperature, { ros2: true }));

const rosImu = (m) => ({
  header: { stamp: { sec: m.sec, nanosec: m.nanosec }, frame_id: m.frame_id },
  orientation: { x: m.orientation[0], y: m.orientation[1], z: m.orientation[2], w: m.orientation[3] },
  orientation_covariance: m.orientation_covariance,
  angular_velocity: { x: m.angular_velocity[0], y: m.angular_velocity[1], z: m.angular_velocity[2] },
  angular_velocity_covariance: m.angular_velocity_covariance,
  linear_acceleration: { x: m.linear_acceleration[0], y: m.linear_acceleration[1], z: m.linear_acceleration[2] },
  linear_acceleration_covariance: m.linear_acceleration_covariance,
});

// The same Imu written field by field with CdrWriter in another encapsulation.
function imuCdr(m, kind) {
  const w = new CdrWriter({ kind });
  w.int32(m.sec); w.uint32(m.nanosec); w.string(m.frame_id);
  for (const v of m.orientation) w.float64(v);
  for (const v of m.orientation_covariance) w.float64(v);
  for (const v of m.angular_velocity) w.float64(v);
  for (const v of m.angular_velocity_covariance) w.float64(v);
  for (const v of m.linear_acceleration) w.float64(v);
  for (const v of m.linear_acceleration_covariance) w.float64(v);
  return w.data;
}

// Synthetic temperature (no thermometer in the source bag): every 10th IMU stamp, 20 degC + 0.05 K
// per sample, variance 0.01.
const temperatures = imu.filter((_, i) => i % 10 === 0).map((m, k) => ({
  time_ns: m.time_ns, sec: m.sec, nanosec: m.nanosec, degc: 20 + 0.05 * k,
}));
const rosTemperature = (t) => ({ header: { stamp: { sec: t.sec, nanosec: t.nanosec }, frame_id: "imu_link" }, temperature: t.degc, variance: 0.01 });

class FileWritable {
  constructor(path) { this.fd = fs.openSync(path, "w"); this.pos = 0n; }
  async write(buffer) { fs.writeSync(this.fd, buffer); this.pos += BigInt(buffer.byteLength); }
  position() { return this.pos; }
  close() { fs.closeSync(this.fd); }
}

const codecs = {
  zstd: (data) => ({ compression: "zstd", compressedData: zstd.compress(data, 19) }),
  lz4: (data) => ({ compression: "lz4", compressedData: Uint8Array.from(lz4.compress(data)) }),
};

async function write(path, { count, codec, chunkSize, summary = true, chunks = true, encode = (m) => imuWriter.writeMessage(rosImu(m)), withTemperature = false }) {
  const file = new FileWritable(path);
  const writer = new McapWriter({
    writable: file, chunkSize, useChunks: chunks, compressChunk: codec ? codecs[codec] : undefined,
    useStatistics: summary, useSummaryOffsets: summary, useMessageIndex: summary, useChunkIndex: summary,
    repeatSchemas: summary, repeatChannels: summary,
  });
  await writer.start({ profile: "ros2", library: "driftlab fixture (@mcap/core)" });
  const imuSchema = await writer.registerSchema({ name: "sensor_msgs/msg/Imu", encoding: "ros2msg", data: new TextEncoder().encode(schemas.imu) });
  const imuChannel = await writer.registerChannel({ topic: "/imu/data", schemaId: imuSchema, messageEncoding: "cdr", metadata: new Map() });
  let temperatureChannel;
  if (withTemperature) {
    const s = await writer.registerSchema({ name: "sensor_msgs/msg/Temperature", encoding: "ros2msg", data: new TextEncoder().encode(schemas.temperature) });
    temperatureChannel = await writer.registerChannel({ topic: "/imu/temperature", schemaId: s, messageEncoding: "cdr", metadata: new Map() });
  }
  const selected = imu.slice(0, count);
  let sequence = 0;
  for (const [i, m] of selected.entries()) {
    const t = BigInt(m.time_ns);
    await writer.addMessage({ channelId: imuChannel, sequence: sequence++, logTime: t, publishTime: t, data: encode(m) });
    if (withTemperature && i % 10 === 0) {
      const tt = temperatures[i / 10];
      await writer.addMessage({ channelId: temperatureChannel, sequence: sequence++, logTime: t, publishTime: t, data: temperatureWriter.writeMessage(rosTemperature(tt)) });
    }
  }
  await writer.end();
  file.close();
}

const short = 500;  // 10 s of the 50 Hz IMU for the variants
await write("imu_zstd.mcap", { count: imu.length, codec: "zstd", chunkSize: 256 * 1024, withTemperature: true });
await write("imu_lz4.mcap", { count: short, codec: "lz4", chunkSize: 64 * 1024 });
await write("imu_uncompressed_chunks.mcap", { count: short, chunkSize: 16 * 1024 });
await write("imu_no_summary_no_chunks.mcap", { count: short, summary: false, chunks: false });
await write("imu_big_endian.mcap", { count: short, codec: "zstd", chunkSize: 256 * 1024, encode: (m) => imuCdr(m, EncapsulationKind.CDR_BE) });
await write("imu_xcdr2.mcap", { count: short, codec: "zstd", chunkSize: 256 * 1024, encode: (m) => imuCdr(m, EncapsulationKind.RTPS_CDR2_LE) });

const b64 = (u8) => Buffer.from(u8).toString("base64");
// rosbag2's compression_mode MESSAGE: each message's CDR bytes one zstd frame (level 3, rosbag2's default).
const zstdB64 = (u8) => b64(zstd.compress(u8, 3));
fs.writeFileSync("cdr_messages.json", JSON.stringify({
  imu: imu.slice(0, short).map((m) => ({ time_ns: m.time_ns, data: b64(imuWriter.writeMessage(rosImu(m))) })),
  temperature: temperatures.slice(0, short / 10).map((t) => ({ time_ns: t.time_ns, data: b64(temperatureWriter.writeMessage(rosTemperature(t))) })),
  imu_zstd: imu.slice(0, 100).map((m) => ({ time_ns: m.time_ns, data: zstdB64(imuWriter.writeMessage(rosImu(m))) })),
}));
