#!/usr/bin/python3
"""Generates the C++ source of a format v1 recording compiled into flash for the
MPS2 image (layout: hal/mps2/flash_recording.hpp).

Every value is converted exactly as the host reader (tools/dataset) converts it:
numbers parse to double (correctly rounded), floats are the double rounded to
float (emitted as exact hex-float literals), times are llround(t_s * 1e6) us.
The generator is strict where the reader is lenient: a row the reader would
skip (bad number, wrong column count, time going backwards, ...) is an error
here, so the image and the host replay always see the same samples.

usage: gen_flash_recording.py RECORDING_DIR OUT.cpp
"""
import math
import os
import re
import struct
import sys

NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")
UINT = re.compile(r"^\+?\d+$")

ANCHORS = (["anchor_id", "x_m", "y_m", "z_m"], [])
TAGS = (["tag_id", "x_m", "y_m", "z_m"], [])
UWB = (["t_s", "anchor_id", "range_m"], ["tag_id", "nlos", "fp_power_dbm", "rx_power_dbm"])
IMU = (["t_s", "ax_mps2", "ay_mps2", "az_mps2", "gx_radps", "gy_radps", "gz_radps"], [])
MAX_ANCHORS = 16  # estimator/types.hpp kMaxAnchors
MAX_TAGS = 4      # estimator/types.hpp kMaxTags


class RecordingError(Exception):
    pass


def parse_double(cell, where):
    if not NUMBER.match(cell):
        raise RecordingError(f"{where}: not a number '{cell}'")
    v = float(cell)
    if not math.isfinite(v):
        raise RecordingError(f"{where}: not finite '{cell}'")
    return v


def to_float32(v, where):
    try:
        return struct.unpack("<f", struct.pack("<f", v))[0]
    except OverflowError:
        raise RecordingError(f"{where}: out of float range") from None


def parse_float(cell, where):
    return to_float32(parse_double(cell, where), where)


def parse_uint(cell, max_value, where):
    if not UINT.match(cell):
        raise RecordingError(f"{where}: not a non-negative integer '{cell}'")
    v = int(cell.lstrip("+"))
    if v > max_value:
        raise RecordingError(f"{where}: out of range '{cell}'")
    return v


def seconds_to_us(t_s):
    """tools/dataset seconds_to_us: llround(t_s * 1e6) (half away from zero)."""
    if not t_s > 0.0:
        return 0
    x = t_s * 1e6
    whole = math.floor(x)
    return int(whole) + (1 if x - whole >= 0.5 else 0)


def read_table(path, columns, required):
    """Rows (lists of trimmed cells) of a format v1 CSV; None when absent and optional."""
    name = os.path.basename(path)
    if not os.path.exists(path):
        if required:
            raise RecordingError(f"{name}: required file missing")
        return None
    with open(path, "rb") as f:
        text = f.read().decode("utf-8-sig")
    want_req, want_opt = columns
    header = None
    rows = []
    for line_no, line in enumerate(text.split("\n"), start=1):
        line = line[:-1] if line.endswith("\r") else line
        if line.strip(" \t") == "" or line.strip(" \t").startswith("#"):
            continue
        cells = [c.strip(" \t") for c in line.split(",")]
        if header is None:
            full = want_req + want_opt
            if not (len(want_req) <= len(cells) <= len(full)) or cells != full[: len(cells)]:
                raise RecordingError(f"{name}:{line_no}: wrong header '{line}'")
            header = cells
            continue
        if len(cells) != len(header):
            raise RecordingError(f"{name}:{line_no}: expected {len(header)} columns, got {len(cells)}")
        rows.append((f"{name}:{line_no}", cells))
    if header is None:
        raise RecordingError(f"{name}: no header line")
    return rows


def read_meta(path):
    meta = {}
    if not os.path.exists(path):
        return meta
    with open(path, "rb") as f:
        text = f.read().decode("utf-8-sig")
    for line_no, line in enumerate(text.split("\n"), start=1):
        line = line.rstrip("\r").strip(" \t")
        if not line or line[0] in "#;":
            continue
        if "=" not in line:
            raise RecordingError(f"meta.ini:{line_no}: not a 'key = value' line")
        key, value = (s.strip(" \t") for s in line.split("=", 1))
        meta[key] = (value, f"meta.ini:{line_no}")
    return meta


def read_times(rows, what):
    last = None
    out = []
    for where, cells in rows:
        t_s = parse_double(cells[0], where)
        if t_s < 0.0 or t_s > 1.8e13:
            raise RecordingError(f"{where}: time out of range")
        t = seconds_to_us(t_s)
        if last is not None and t < last:
            raise RecordingError(f"{where}: {what} time goes backwards")
        last = t
        out.append(t)
    return out


def hexf(v):
    """Exact C++ float literal of a float32 value held in a Python float."""
    if math.isnan(v):
        return "kNaNf"
    sign, digits = ("-", v.hex()[1:]) if v.hex().startswith("-") else ("", v.hex())
    lead, rest = digits[2:].split(".")
    frac, exp = rest.split("p")
    frac = frac.rstrip("0")
    return f"{sign}0x{lead}{'.' + frac if frac else ''}p{exp}F"


def load(rec_dir):
    meta = read_meta(os.path.join(rec_dir, "meta.ini"))
    rec = {"name": os.path.basename(os.path.normpath(rec_dir)), "platform": None, "gravity": None}
    if "name" in meta and meta["name"][0]:
        rec["name"] = meta["name"][0]
    if "platform" in meta:
        value, where = meta["platform"]
        if value not in ("ground", "air"):
            raise RecordingError(f"{where}: platform '{value}' is neither ground nor air")
        rec["platform"] = 0 if value == "ground" else 1
    # uwb_sigma_m is a simulator fact (the true noise level): the firmware never reads it.
    for key, field in (("gravity_mps2", "gravity"),):
        if key in meta:
            value, where = meta[key]
            v = parse_double(value, where)
            if not 0.0 < v <= 100.0:
                raise RecordingError(f"{where}: {key} not in (0, 100]")
            rec[field] = to_float32(v, where)

    anchors = []
    for where, c in read_table(os.path.join(rec_dir, "anchors.csv"), ANCHORS, True):
        a = (parse_uint(c[0], 0xFFFF, where), [parse_float(x, where) for x in c[1:4]])
        if any(a[0] == b[0] for b in anchors):
            raise RecordingError(f"{where}: duplicate anchor_id {a[0]}")
        anchors.append(a)
    if not anchors or len(anchors) > MAX_ANCHORS:
        raise RecordingError(f"anchors.csv: {len(anchors)} anchors (1..{MAX_ANCHORS} supported)")

    tags = []
    tag_rows = read_table(os.path.join(rec_dir, "tags.csv"), TAGS, False)
    for where, c in tag_rows or []:
        t = (parse_uint(c[0], 0xFF, where), [parse_float(x, where) for x in c[1:4]])
        if any(t[0] == b[0] for b in tags):
            raise RecordingError(f"{where}: duplicate tag_id {t[0]}")
        tags.append(t)
    if len(tags) > MAX_TAGS:
        raise RecordingError(f"tags.csv: {len(tags)} tags (at most {MAX_TAGS} supported)")
    if not tags:
        tags.append((0, [0.0, 0.0, 0.0]))

    uwb_rows = read_table(os.path.join(rec_dir, "uwb.csv"), UWB, True)
    uwb_t = read_times(uwb_rows, "uwb")
    uwb = []
    for (where, c), t in zip(uwb_rows, uwb_t):
        tag = parse_uint(c[3], 0xFF, where) if len(c) > 3 and c[3] else 0
        if len(c) > 4 and c[4]:
            parse_uint(c[4], 1, where)  # label: validated like the reader, never stored
        fp = parse_float(c[5], where) if len(c) > 5 and c[5] else math.nan
        rx = parse_float(c[6], where) if len(c) > 6 and c[6] else math.nan
        uwb.append((t, parse_uint(c[1], 0xFFFF, where), tag, parse_float(c[2], where), fp, rx))

    imu = []
    imu_rows = read_table(os.path.join(rec_dir, "imu.csv"), IMU, False)
    if imu_rows is not None:
        for (where, c), t in zip(imu_rows, read_times(imu_rows, "imu")):
            imu.append((t, [parse_float(x, where) for x in c[1:7]]))
    rec.update(anchors=anchors, tags=tags, uwb=uwb, imu=imu)
    return rec


def emit(rec, src_dir):
    times = [u[0] for u in rec["uwb"]] + [s[0] for s in rec["imu"]]
    base = min(times) if times else 0
    if times and max(times) - base > 0xFFFFFFFF:
        raise RecordingError("recording longer than 4294 s (dt_us is 32-bit)")
    name = re.sub(r'[^A-Za-z0-9_.+-]', "_", rec["name"])
    out = [
        f"// Format v1 recording '{name}' compiled into flash. Generated by",
        f"// hal/mps2/gen_flash_recording.py from {os.path.basename(os.path.normpath(src_dir))}/: do not edit.",
        '#include "hal/mps2/flash_recording.hpp"',
        "",
        "namespace uwbnav::mps2 {",
        "namespace {",
        "",
        "const FlashAnchor kAnchors[] = {",
    ]
    out += [f"    {{{i}, {{{', '.join(hexf(v) for v in p)}}}}}," for i, p in rec["anchors"]]
    out += ["};", "", "const FlashTag kTags[] = {"]
    out += [f"    {{{i}, {{{', '.join(hexf(v) for v in p)}}}}}," for i, p in rec["tags"]]
    out += ["};", ""]
    if rec["imu"]:
        out.append('__attribute__((section(".replay_data.imu"))) const FlashImu kImu[] = {')
        for t, v in rec["imu"]:
            out.append(f"    {{{t - base}U, {{{', '.join(hexf(x) for x in v[:3])}}}, {{{', '.join(hexf(x) for x in v[3:])}}}}},")
        out += ["};", ""]
    if rec["uwb"]:
        out.append('__attribute__((section(".replay_data.uwb"))) const FlashUwb kUwb[] = {')
        for t, anchor, tag, rng, fp, rx in rec["uwb"]:
            out.append(f"    {{{t - base}U, {hexf(rng)}, {hexf(fp)}, {hexf(rx)}, {anchor}, {tag}}},")
        out += ["};", ""]
    platform = "kPlatformUnset" if rec["platform"] is None else str(rec["platform"])
    gravity = "kNaNf" if rec["gravity"] is None else hexf(rec["gravity"])
    out += [
        "}  // namespace",
        "",
        "const FlashRecording kFlashRecording = {",
        f'    "{name}",',
        f"    {base}ULL,",
        f"    kAnchors, {len(rec['anchors'])},",
        f"    kTags, {len(rec['tags'])},",
        f"    {platform},",
        f"    {gravity},",
        f"    {'kImu' if rec['imu'] else 'nullptr'}, {len(rec['imu'])},",
        f"    {'kUwb' if rec['uwb'] else 'nullptr'}, {len(rec['uwb'])},",
        "};",
        "",
        "}  // namespace uwbnav::mps2",
        "",
    ]
    return "\n".join(out)


def main(argv):
    if len(argv) != 3:
        sys.stderr.write(__doc__.split("\n\n")[-1])
        return 2
    rec_dir, out_path = argv[1], argv[2]
    try:
        text = emit(load(rec_dir), rec_dir)
    except RecordingError as e:
        sys.stderr.write(f"gen_flash_recording: {rec_dir}: {e}\n")
        return 1
    tmp = out_path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, out_path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
