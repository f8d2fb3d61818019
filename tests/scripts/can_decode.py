#!/usr/bin/python3
"""Checks a uwbnav candump log with tools nobody here wrote.

Reads OUT/can.log with python-can (CanutilsLogReader), decodes every frame with
canmatrix using docs/uwbnav.dbc, and checks:
  * every frame's id is in the DBC and its CRC-8 SAE J1850 verifies (recomputed
    here over E2EDataID low byte, high byte, payload bytes 1..7, as the DBC says);
  * each message's alive counter advances 0..14 by exactly 1 (15 never sent);
  * every decoded PosX/PosY/PosZ/VelX/VelY/VelZ/Sigma* value matches the row of
    estimates.csv with the same time (UWBNAV_NavTime) within half the DBC
    resolution, or is clipped and flagged (Saturated) when out of range / empty;
  * the status signals equal the estimates.csv status;
  * the observed period of each cyclic message equals its GenMsgCycleTime;
  * cooperative state groups (UWBNAV_Coop*, when the log has them): the six
    parts follow UWBNAV_CoopTime in the same cycle with its alive counter,
    Coop_Valid = 1, the estimates.csv row at Coop_TimeUs has status valid or
    degraded, and velocities and sigmas match it within half the DBC resolution
    (positions too with --coop-tag-at-origin: the tag lever arm is zero).
Usage: can_decode.py --dbc docs/uwbnav.dbc --log OUT/can.log --estimates OUT/estimates.csv
Exit status 0 when every check passes, 1 otherwise. --mutate {crc,counter,position}
corrupts the input in memory (negative controls: the check must then fail).
"""

import argparse
import csv
import statistics
import sys

import can
import canmatrix
import canmatrix.formats

# AUTOSAR CRC library check values for CRC-8 SAE J1850.
CRC_VECTORS = [
    (bytes([0x00, 0x00, 0x00, 0x00]), 0x59),
    (bytes([0xF2, 0x01, 0x83]), 0x37),
    (bytes([0x0F, 0xAA, 0x00, 0x55]), 0x79),
    (bytes([0x00, 0xFF, 0x55, 0x11]), 0xB8),
    (bytes([0x33, 0x22, 0x55, 0xAA, 0xBB, 0xCC, 0xDD, 0xEE, 0xFF]), 0xCB),
    (bytes([0x92, 0x6B, 0x55]), 0x8C),
    (bytes([0xFF, 0xFF, 0xFF, 0xFF]), 0x74),
]

# Output signal -> estimates.csv column (position, velocity, sigma).
COMPARED = {
    "UWBNAV_PosXY": [("PosX", "x_m"), ("PosY", "y_m")],
    "UWBNAV_PosZ": [("PosZ", "z_m"), ("VelZ", "vz_mps")],
    "UWBNAV_VelHdg": [("VelX", "vx_mps"), ("VelY", "vy_mps")],
    "UWBNAV_Accuracy": [("SigmaX", "sx_m"), ("SigmaY", "sy_m"), ("SigmaZ", "sz_m")],
}
STATUS_SIGNALS = {"UWBNAV_PosXY": "PosXY_Status", "UWBNAV_PosZ": "PosZ_Status"}
NAV_TIME = "UWBNAV_NavTime"
COOP_TIME = "UWBNAV_CoopTime"
# Cooperative state parts -> (signal, estimates.csv column, is a tag position).
COOP_COMPARED = {
    "UWBNAV_CoopPosX": [("Coop_PosX", "x_m", True), ("Coop_VelX", "vx_mps", False)],
    "UWBNAV_CoopPosY": [("Coop_PosY", "y_m", True), ("Coop_VelY", "vy_mps", False)],
    "UWBNAV_CoopPosZ": [("Coop_PosZ", "z_m", True), ("Coop_VelZ", "vz_mps", False)],
    "UWBNAV_CoopSigma": [("Coop_SigmaX", "sx_m", False), ("Coop_SigmaY", "sy_m", False), ("Coop_SigmaZ", "sz_m", False)],
    "UWBNAV_CoopCorr": [],
}
# Frames paired with NavTime by equal alive counter (docs/can.md).
SAME_COUNTER_AS_NAV_TIME = ("UWBNAV_PosXY", "UWBNAV_PosZ", "UWBNAV_VelHdg")


def crc8_j1850(data):
    crc = 0xFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


def seconds_to_us(text):
    whole, _, frac = text.strip().partition(".")
    return int(whole) * 1000000 + int((frac + "000000")[:6] or "0")


def read_estimates(path):
    rows = {}
    with open(path, newline="") as f:
        reader = csv.DictReader(row for row in f if not row.startswith("#"))
        for row in reader:
            rows[seconds_to_us(row["t_s"])] = row
    return rows


class Checker:
    def __init__(self, db, estimates, coop_tag_at_origin=False):
        self.db = db
        self.estimates = estimates
        self.by_t32 = {t & 0xFFFFFFFF: row for t, row in estimates.items()}
        self.coop_tag_at_origin = coop_tag_at_origin
        self.coop = None  # (log timestamp, Coop_TimeUs, counter) of the latest UWBNAV_CoopTime
        self.frames_by_id = {f.arbitration_id.id: f for f in db.frames}
        self.errors = []
        self.counts = {"frames": 0, "crc_ok": 0, "compared": 0, "saturated": 0, "positions": 0,
                       "error_frames": 0, "coop_groups": 0}
        self.last_counter = {}
        self.stamps = {}
        self.group = None  # (log timestamp, nav_t_us, counter) of the latest NavTime

    def fail(self, msg):
        if len(self.errors) < 50:
            print("FAIL: " + msg)
        self.errors.append(msg)

    def signal_value(self, decoded, name):
        return decoded[name].raw_value, float(decoded[name].phys_value)

    def check_frame(self, msg):
        self.counts["frames"] += 1
        if msg.is_error_frame:
            self.counts["error_frames"] += 1
            return
        frame = self.frames_by_id.get(msg.arbitration_id)
        if frame is None or msg.is_extended_id:
            self.fail("t=%.6f: id 0x%X is not in the DBC" % (msg.timestamp, msg.arbitration_id))
            return
        data = bytes(msg.data)
        if len(data) != frame.size:
            self.fail("%s: %d bytes, DBC says %d" % (frame.name, len(data), frame.size))
            return
        decoded = frame.decode(data)
        prefix = frame.signals[0].name.rsplit("_", 1)[0]
        crc_sig = decoded[prefix + "_CRC"].raw_value
        counter = decoded[prefix + "_AliveCounter"].raw_value
        saturated = decoded[prefix + "_Saturated"].raw_value
        data_id = int(frame.attribute("E2EDataID", self.db))
        expected_crc = crc8_j1850(bytes([data_id & 0xFF, data_id >> 8]) + data[1:])
        if crc_sig != expected_crc:
            self.fail("t=%.6f %s: CRC 0x%02X, recomputed 0x%02X" % (msg.timestamp, frame.name, crc_sig, expected_crc))
        else:
            self.counts["crc_ok"] += 1
        if counter > 14:
            self.fail("t=%.6f %s: alive counter %d (15 is never sent)" % (msg.timestamp, frame.name, counter))
        prev = self.last_counter.get(frame.name)
        if prev is not None and counter != (prev + 1) % 15:
            self.fail("t=%.6f %s: alive counter %d after %d (gap or repeat)" % (msg.timestamp, frame.name, counter, prev))
        self.last_counter[frame.name] = counter
        self.stamps.setdefault(frame.name, []).append(msg.timestamp)

        if frame.name == NAV_TIME:
            self.group = (msg.timestamp, int(decoded["NavTime_Us"].raw_value), counter)
            return
        if frame.name == COOP_TIME:
            self.coop = (msg.timestamp, int(decoded["Coop_TimeUs"].raw_value), counter)
            self.counts["coop_groups"] += 1
            if decoded["Coop_Valid"].raw_value != 1:
                self.fail("t=%.6f %s: Coop_Valid=0 from UWBNAV" % (msg.timestamp, frame.name))
            return
        if frame.name in COOP_COMPARED:
            self.check_coop_part(msg, frame, decoded, counter, saturated)
            return
        if frame.name not in COMPARED:
            return
        if self.group is None or abs(self.group[0] - msg.timestamp) > 1e-7:
            self.fail("t=%.6f %s: no NavTime frame in the same cycle" % (msg.timestamp, frame.name))
            return
        if frame.name in SAME_COUNTER_AS_NAV_TIME and counter != self.group[2]:
            self.fail("t=%.6f %s: counter %d differs from NavTime's %d" % (msg.timestamp, frame.name, counter, self.group[2]))
        nav_t_us = self.group[1]
        row = self.estimates.get(nav_t_us)
        if row is None:
            self.fail("%s: no estimates.csv row at t=%d us" % (frame.name, nav_t_us))
            return
        if frame.name == "UWBNAV_PosXY":
            self.counts["positions"] += 1
        if frame.name in STATUS_SIGNALS:
            status = decoded[STATUS_SIGNALS[frame.name]].raw_value
            if str(status) != row["status"].strip():
                self.fail("t=%d us %s: status %d, estimates.csv %s" % (nav_t_us, frame.name, status, row["status"]))
        expect_flag = False
        for sig_name, column in COMPARED[frame.name]:
            sig = frame.signal_by_name(sig_name)
            factor = float(sig.factor)
            lo, hi = float(sig.min), float(sig.max)
            _, phys = self.signal_value(decoded, sig_name)
            cell = row[column].strip()
            if cell == "":  # not finite in the firmware: sent flagged
                expect_flag = True
                continue
            value = float(cell)
            if value < lo - factor / 2 or value > hi + factor / 2:
                expect_flag = True
                target = min(max(value, lo), hi)
                if abs(phys - target) > factor / 2 + 1e-9:
                    self.fail("t=%d us %s: %s=%r not clipped to %r" % (nav_t_us, frame.name, sig_name, phys, target))
                continue
            self.counts["compared"] += 1
            if abs(phys - value) > factor / 2 + 1e-9:
                self.fail("t=%d us %s: %s=%r, estimates.csv %s=%r (resolution %g)" %
                          (nav_t_us, frame.name, sig_name, phys, column, value, factor))
        if saturated:
            self.counts["saturated"] += 1
        if expect_flag and not saturated:
            self.fail("t=%d us %s: out-of-range/empty value but Saturated=0" % (nav_t_us, frame.name))

    def check_coop_part(self, msg, frame, decoded, counter, saturated):
        if self.coop is None or abs(self.coop[0] - msg.timestamp) > 1e-7:
            self.fail("t=%.6f %s: no UWBNAV_CoopTime frame in the same cycle" % (msg.timestamp, frame.name))
            return
        if counter != self.coop[2]:
            self.fail("t=%.6f %s: counter %d differs from CoopTime's %d" % (msg.timestamp, frame.name, counter, self.coop[2]))
        row = self.by_t32.get(self.coop[1])
        if row is None:
            self.fail("%s: no estimates.csv row with low 32 bits of t = %d us" % (frame.name, self.coop[1]))
            return
        if row["status"].strip() not in ("1", "2"):
            self.fail("%s: sent for an estimate with status %s (only valid/degraded)" % (frame.name, row["status"]))
        if saturated:
            self.counts["saturated"] += 1
        for sig_name, column, is_position in COOP_COMPARED[frame.name]:
            if is_position and not self.coop_tag_at_origin:
                continue
            sig = frame.signal_by_name(sig_name)
            factor = float(sig.factor)
            raw = decoded[sig_name].raw_value
            phys = float(decoded[sig_name].phys_value)
            cell = row[column].strip()
            if cell == "":
                if sig_name.startswith("Coop_Vel") and raw == -(1 << (int(sig.size) - 1)):
                    continue  # not reported: the code, not a value
                if not saturated:
                    self.fail("%s: %s empty in estimates.csv but sent as %r without Saturated" % (frame.name, column, phys))
                continue
            self.counts["compared"] += 1
            if abs(phys - float(cell)) > factor / 2 + 1e-9:
                self.fail("t=%d us %s: %s=%r, estimates.csv %s=%s (resolution %g)" %
                          (self.coop[1], frame.name, sig_name, phys, column, cell, factor))

    def check_periods(self):
        for frame in self.db.frames:
            stamps = self.stamps.get(frame.name, [])
            cycle_ms = frame.cycle_time
            if cycle_ms and len(stamps) > 2:
                period_ms = 1000.0 * statistics.median(b - a for a, b in zip(stamps, stamps[1:]))
                if abs(period_ms - cycle_ms) > 0.1 * cycle_ms:
                    self.fail("%s: observed period %.3f ms, GenMsgCycleTime %d ms" % (frame.name, period_ms, cycle_ms))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dbc", required=True)
    ap.add_argument("--log", required=True)
    ap.add_argument("--estimates", required=True)
    ap.add_argument("--min-positions", type=int, default=1, help="fail when fewer PosXY frames were checked")
    ap.add_argument("--min-coop-groups", type=int, default=0, help="fail when fewer UWBNAV_Coop* groups were checked")
    ap.add_argument("--coop-tag-at-origin", action="store_true",
                    help="the publisher's tag lever arm is zero: compare Coop_Pos* with the estimates too")
    ap.add_argument("--mutate", choices=["crc", "counter", "position"],
                    help="negative control: flip a payload bit / drop a frame / move one estimate by 2 mm")
    args = ap.parse_args()

    for data, crc in CRC_VECTORS:
        if crc8_j1850(data) != crc:
            print("FAIL: CRC-8 J1850 self-test %s -> 0x%02X, expected 0x%02X" % (data.hex(), crc8_j1850(data), crc))
            return 1

    db = canmatrix.formats.loadp_flat(args.dbc)
    if db is None or not db.frames:
        print("FAIL: canmatrix could not load %s" % args.dbc)
        return 1
    estimates = read_estimates(args.estimates)
    if args.mutate == "position":
        row = estimates[sorted(estimates)[len(estimates) // 2]]
        row["x_m"] = repr(float(row["x_m"]) + 0.002)
    checker = Checker(db, estimates, args.coop_tag_at_origin)
    for index, msg in enumerate(can.CanutilsLogReader(args.log)):
        if args.mutate == "counter" and index == 100:
            continue
        if args.mutate == "crc" and index == 100:
            msg.data[3] ^= 0x04
        checker.check_frame(msg)
    checker.check_periods()

    c = checker.counts
    print("can_decode: python-can %s, canmatrix %s, %d frames, %d CRCs verified, %d PosXY frames, "
          "%d coop groups, %d values compared, %d saturated frames, %d error frames, %d estimates rows"
          % (can.__version__, getattr(canmatrix, "__version__", "?"), c["frames"], c["crc_ok"], c["positions"],
             c["coop_groups"], c["compared"], c["saturated"], c["error_frames"], len(checker.estimates)))
    for name in sorted(checker.last_counter):
        print("  %-16s %6d frames" % (name, len(checker.stamps[name])))
    if c["positions"] < args.min_positions:
        checker.fail("only %d PosXY frames checked (need %d)" % (c["positions"], args.min_positions))
    if c["coop_groups"] < args.min_coop_groups:
        checker.fail("only %d UWBNAV_Coop* groups checked (need %d)" % (c["coop_groups"], args.min_coop_groups))
    if checker.errors:
        print("can_decode: %d check(s) failed" % len(checker.errors))
        return 1
    print("can_decode: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
