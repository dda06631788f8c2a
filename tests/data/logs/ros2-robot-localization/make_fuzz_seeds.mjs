// Seeds of the libFuzzer harnesses tests/fuzz/fuzz_mcap.cpp and fuzz_ros_messages.cpp, from the
// fixtures of this folder (run by make_fixtures.sh after them): small MCAP files (the first 8 IMU
// messages of the Jackal recording, plus 2 temperatures, in each layout the fixtures have: zstd,
// lz4 and uncompressed chunks with summary, unchunked without summary, big-endian CDR, XCDR2) and
// single serialized messages (CDR in three encapsulations; the ROS 1 bytes come from
// ../ros1-robot-localization via python3-rosbag). Each seed starts with the harness's mode byte.
import fs from "node:fs";
import { McapStreamReader, McapWriter } from "@mcap/core";
import zstd from "@foxglove/wasm-zstd";
import lz4 from "lz4js";
import lz4d from "@foxglove/wasm-lz4";

await zstd.isLoaded;
await lz4d.isLoaded;
const out = "../../../fuzz/corpus";
fs.mkdirSync(`${out}/mcap`, { recursive: true });
fs.mkdirSync(`${out}/ros_messages`, { recursive: true });

function records(file) {
  const reader = new McapStreamReader({ decompressHandlers: { zstd: (d, n) => zstd.decompress(d, Number(n)), lz4: (d, n) => lz4d(d, Number(n)) } });
  reader.append(fs.readFileSync(file));
  const all = [];
  let r;
  while ((r = reader.nextRecord())) all.push(r);
  return all;
}

class Memory {
  constructor() { this.parts = []; this.pos = 0n; }
  async write(b) { this.parts.push(Buffer.from(b)); this.pos += BigInt(b.byteLength); }
  position() { return this.pos; }
  bytes() { return Buffer.concat(this.parts); }
}

async function seed(name, source, options, count = 8) {
  const all = records(source);
  const memory = new Memory();
  const writer = new McapWriter({ writable: memory, ...options });
  await writer.start({ profile: "ros2", library: "driftlab fuzz seed" });
  const schemas = new Map(), channels = new Map();
  for (const r of all) {
    if (r.type === "Schema") schemas.set(r.id, await writer.registerSchema({ name: r.name, encoding: r.encoding, data: r.data }));
    if (r.type === "Channel") channels.set(r.id, await writer.registerChannel({ topic: r.topic, schemaId: schemas.get(r.schemaId), messageEncoding: r.messageEncoding, metadata: r.metadata }));
  }
  let n = 0;
  for (const r of all)
    if (r.type === "Message" && n++ < count + 2) await writer.addMessage({ ...r, channelId: channels.get(r.channelId) });
  await writer.end();
  for (const mode of [0, 3]) fs.writeFileSync(`${out}/mcap/${name}_mode${mode}.mcap`, Buffer.concat([Buffer.from([mode]), memory.bytes()]));
}

await seed("zstd_temperature", "imu_zstd.mcap", { compressChunk: (d) => ({ compression: "zstd", compressedData: zstd.compress(d, 19) }) });
await seed("lz4", "imu_lz4.mcap", { chunkSize: 1024, compressChunk: (d) => ({ compression: "lz4", compressedData: Uint8Array.from(lz4.compress(d)) }) });
await seed("uncompressed", "imu_uncompressed_chunks.mcap", { chunkSize: 1024 });
await seed("no_summary", "imu_no_summary_no_chunks.mcap", { useChunks: false, useStatistics: false, useSummaryOffsets: false, useMessageIndex: false, useChunkIndex: false, repeatSchemas: false, repeatChannels: false });
await seed("big_endian", "imu_big_endian.mcap", {});
await seed("xcdr2", "imu_xcdr2.mcap", {});

// Mode byte of fuzz_ros_messages: bits 0-1 the type (Imu, Temperature, Float32, Float64), bit 2 ROS 1.
const first = (file, topic) => records(file).find((r) => r.type === "Message" && r.channelId === records(file).find((c) => c.type === "Channel" && c.topic === topic).id).data;
const message = (name, mode, data) => fs.writeFileSync(`${out}/ros_messages/${name}`, Buffer.concat([Buffer.from([mode]), Buffer.from(data)]));
message("imu_cdr_le", 0, first("imu_zstd.mcap", "/imu/data"));
message("imu_cdr_be", 0, first("imu_big_endian.mcap", "/imu/data"));
message("imu_xcdr2", 0, first("imu_xcdr2.mcap", "/imu/data"));
message("temperature_cdr_le", 1, first("imu_zstd.mcap", "/imu/temperature"));
