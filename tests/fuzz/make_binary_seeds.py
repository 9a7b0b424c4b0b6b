#!/usr/bin/env python3
"""Writes the binary seeds of tests/fuzz/corpus: raw force_block_t messages (force_block/) and
small lcm-logger logs of them (lcm_log_reader/), valid and near-valid. Run from anywhere; the
seeds are committed, this script only says how they were made."""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
SYNC = 0xEDA1DA01
# lcm-gen's fingerprint of millwatch.force_block_t (build/*/msgs/include/.../force_block_t.hpp).
BASE = 0xEE08C26B45BEC261
HASH = ((BASE << 1) + ((BASE >> 63) & 1)) & 0xFFFFFFFFFFFFFFFF


def block(utime, seq, rate, fx, fy=None, fz=None, count=None, fingerprint=HASH):
    fy = fx if fy is None else fy
    fz = fx if fz is None else fz
    n = len(fx) if count is None else count
    out = struct.pack(">QqqdI", fingerprint, utime, seq, rate, n & 0xFFFFFFFF)
    for channel in (fx, fy, fz):
        out += b"".join(struct.pack(">d", v) for v in channel)
    return out


def event(number, utime, channel, data):
    c = channel.encode()
    return struct.pack(">IqqII", SYNC, number, utime, len(c), len(data)) + c + data


def write(folder, name, data):
    path = os.path.join(HERE, "corpus", folder, name)
    with open(path, "wb") as f:
        f.write(data)


raw = "MILLWATCH_FORCE_RAW"
b0 = block(0, 0, 50000.0, [0.5, -1.0, 2.0, 0.0])
b1 = block(80, 1, 50000.0, [1.0, float("nan"), float("inf"), 1e306])
b2 = block(160, 2, 50000.0, [])
b3 = block(240, 3, 20000.0, [3.0, 4.0])
write("force_block", "four_samples.bin", b0)
write("force_block", "nonfinite.bin", b1)
write("force_block", "empty.bin", b2)
write("force_block", "wrapped_count.bin", block(0, 0, 50000.0, [1.0], count=(1 << 29) + 1))
write("force_block", "negative_count.bin", block(0, 0, 50000.0, [1.0, 2.0], count=-1))
write("force_block", "short.bin", b0[:-3])
write("force_block", "other_type.bin", block(0, 0, 50000.0, [1.0], fingerprint=HASH ^ 1))
write("force_block", "extreme_utime.bin", block(-(1 << 63), 7, 50000.0, [1.0, 2.0]))

write("lcm_log_reader", "three_events.lcmlog",
      event(0, 0, raw, b0) + event(1, 80, raw, b1) + event(2, 160, raw, b2))
write("lcm_log_reader", "other_channel.lcmlog",
      event(0, 0, raw, b0) + event(1, 5, "MILLWATCH_STATUS", b"\x01\x02\x03") +
      event(2, 240, raw, b3))
write("lcm_log_reader", "bad_count.lcmlog",
      event(0, 0, raw, block(0, 0, 50000.0, [1.0], count=(1 << 28) + 1)) + event(1, 80, raw, b0))
write("lcm_log_reader", "broken_sync.lcmlog",
      event(0, 0, raw, b0) + b"\xed\x00\xda\x01" + event(1, 80, raw, b1)[4:] + event(2, 160, raw, b0))
write("lcm_log_reader", "truncated.lcmlog", event(0, 0, raw, b0) + event(1, 80, raw, b1)[:40])
write("lcm_log_reader", "time_jumps.lcmlog",
      event(0, 0, raw, block(1 << 53, 0, 50000.0, [1.0])) +
      event(1, 0, raw, block(-(1 << 53), 1, 50000.0, [1.0])) +
      event(2, 0, raw, block((1 << 63) - 1, 2, 50000.0, [1.0])))
