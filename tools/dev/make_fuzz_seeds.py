#!/usr/bin/env python3
"""Writes the seed corpora of the libFuzzer targets (test/fuzz_corpus/).

Each seed is a small valid input of the format a target reads, built from
the public protocol descriptions (P2OS packets, LMS2xx telegrams, CARMEN
lines, the landmark-map file), so that the fuzzers start past the first
checksum. Targets whose input is structured by FuzzedDataProvider get a few
fixed pseudo-random byte strings. Run from the repository root:
    tools/dev/make_fuzz_seeds.py
"""
import os
import random
import struct

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "test", "fuzz_corpus")


def write(target, name, data):
    folder = os.path.join(ROOT, target)
    os.makedirs(folder, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(folder, name), "wb") as f:
        f.write(data)


def p2os_packet(payload):
    """0xFA 0xFB | LEN | payload | checksum (big-endian byte pairs, odd byte XORed)."""
    checksum = 0
    for i in range(0, len(payload) - 1, 2):
        checksum = (checksum + ((payload[i] << 8) | payload[i + 1])) & 0xFFFF
    if len(payload) % 2:
        checksum ^= payload[-1]
    return bytes([0xFA, 0xFB, len(payload) + 2]) + bytes(payload) + bytes([checksum >> 8, checksum & 0xFF])


def lms_crc(data):
    crc, prev = 0, 0
    for cur in data:
        if crc & 0x8000:
            crc = ((crc & 0x7FFF) << 1) ^ 0x8005
        else:
            crc = crc << 1
        crc = (crc ^ (cur | (prev << 8))) & 0xFFFF
        prev = cur
    return crc


def lms_telegram(address, command, data):
    body = bytes([0x02, address]) + struct.pack("<H", 1 + len(data)) + bytes([command]) + bytes(data)
    return body + struct.pack("<H", lms_crc(body))


def main():
    # P3-DX: first byte = chunk size; then a SYNC reply and two standard SIPs.
    sip = [0x32] + list(struct.pack("<HHhhhB", 1000, 2000, 512, 100, 100, 120)) + [0] * 20
    stream = p2os_packet([0]) + p2os_packet(sip) + p2os_packet([0x33] + sip[1:])
    write("p3dx_packet_fuzzer", "sync_and_sips", bytes([7]) + stream)
    write("p3dx_packet_fuzzer", "enable", bytes([1]) + p2os_packet([4, 0x3B, 1, 0]))

    # LMS200 decoder: first byte = address bit, interlace bit and chunking.
    ranges = [1000 + 10 * i for i in range(181)]
    values = struct.pack("<H", 181 | (1 << 14)) + b"".join(struct.pack("<H", r) for r in ranges)
    scan = bytes([0x06]) + lms_telegram(0x80, 0xB0, values + bytes([0x10]))
    write("lms200_decoder_fuzz", "scan_181_mm", bytes([1 | (3 << 2)]) + scan)
    write("lms200_decoder_fuzz", "ack_mode_reply",
          bytes([1]) + bytes([0x06]) + lms_telegram(0x80, 0xA0, [0, 0x10]))
    write("lms200_decoder_fuzz", "host_install",
          bytes([0]) + lms_telegram(0x00, 0x20, [0x00] + list(b"SICK_LMS")))

    # LMS200 session, the pipeline and the LaserScan boundary: FuzzedDataProvider
    # input, any bytes.
    rng = random.Random(7)
    for i in range(4):
        write("lms200_session_fuzz", "random_%d" % i, bytes(rng.randrange(256) for _ in range(64 << i)))
        write("slam_pipeline_fuzz", "random_%d" % i, bytes(rng.randrange(256) for _ in range(64 << i)))
    rng = random.Random(11)
    for i in range(4):
        write("laser_scan_fuzz", "random_%d" % i, bytes(rng.randrange(256) for _ in range(64 << i)))

    # CARMEN lines.
    flaser = "FLASER 5 1.0 1.1 1.2 1.3 1.4 0.1 0.2 0.3 0.1 0.2 0.3 12.5 host 12.6\n"
    odom = "ODOM 1.0 2.0 0.5 0.1 0.0 0.0 12.4 host 12.4\n"
    robotlaser = ("ROBOTLASER1 0 -1.5708 3.1416 0.7854 80 0.01 0 5 2.0 2.1 2.2 2.3 2.4 0 "
                  "0.1 0.2 0.3 0.1 0.2 0.3 0.0 0.0 0.5 0.5 0.0 13.0 host 13.0\n")
    write("carmen_log_fuzz", "mixed", "# a comment\nPARAM robot_name pioneer\n" + odom + flaser + robotlaser)
    write("carmen_log_fuzz", "odom", odom)

    # Landmark maps.
    write("landmark_map_fuzz", "two", "# map\nversion: 1\nframe: map\ncount: 2\nlandmarks:\n"
          "  - {id: 3, x: 1.25, y: -0.5, covariance: [0.01, 0.001, 0.001, 0.02], observations: 7}\n"
          "  - {id: 9, x: -4, y: 2.5e1, covariance: [0.04, 0, 0.04]}\n")
    write("landmark_map_fuzz", "empty", "version: 1\nframe: odom\ncount: 0\nlandmarks:\n")
    write("landmark_map_fuzz", "every_kind",
          "version: 2\nframe: map\ncount: 5\nlandmarks:\n"
          "  - {id: 3, x: 6, y: -3, covariance: [0.01, 0.001, 0.001, 0.02], observations: 7}\n"
          "  - {id: 4, x: 6, y: 4, covariance: [0.02, 0, 0, 0.02]}\n"
          "lines:\n"
          "  - {id: 5, p: 2.5, theta: 1.5707963267948966, covariance: [4e-4, 1e-5, 1e-5, 1e-4], "
          "observations: 12, extent: [-1.5, 3]}\n"
          "  - {id: 6, p: 0, theta: -3.141592653589793, covariance: [1e-3, 0, 0, 1e-3]}\n"
          "line_angles:\n"
          "  - {id: 8, theta: 0, variance: 1e-4, observations: 9, endpoints: [3, 4]}\n")
    write("landmark_map_fuzz", "lines_only",
          "version: 2\nframe: map\ncount: 1\nlandmarks: []\nlines: []\nline_angles:\n"
          "  - {id: 0, theta: 3.14, variance: 9.8, endpoints: [-1, -1]}\n")


if __name__ == "__main__":
    main()
