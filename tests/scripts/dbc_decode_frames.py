#!/usr/bin/python3
"""Decodes CAN frames with canmatrix and a DBC, for tests/can/test_dbc.cpp
(CanDbc.CanmatrixDecodesTheCodecFramesAsTheFirmwareDoes): the C++ codec and the
DBC as a third-party tool reads it must agree on every signal.

Usage: dbc_decode_frames.py DBC FRAMES OUT
FRAMES: one frame per line, 'ID_HEX DATA_HEX'. OUT: one line per signal,
'FRAME_INDEX SIGNAL_NAME RAW PHYS VALUE_NAME' (PHYS as repr(float), VALUE_NAME
from the signal's value table or '-'). Exit 0 on success, 3 when canmatrix is
not installed (the test then skips), 1 on an unknown id or a decode error.
"""

import sys

try:
    import canmatrix.formats
except ImportError:
    print("dbc_decode_frames: canmatrix is not installed")
    sys.exit(3)


def main():
    if len(sys.argv) != 4:
        print(__doc__)
        return 2
    db = canmatrix.formats.loadp_flat(sys.argv[1])
    frames = {f.arbitration_id.id: f for f in db.frames}
    with open(sys.argv[2]) as src, open(sys.argv[3], "w") as out:
        for index, line in enumerate(src):
            ident, data = line.split()
            frame = frames.get(int(ident, 16))
            if frame is None:
                print("dbc_decode_frames: id %s is not in the DBC" % ident)
                return 1
            for name, sig in frame.decode(bytes.fromhex(data)).items():
                raw = int(sig.raw_value)
                named = sig.signal.values.get(raw, "-")
                out.write("%d %s %d %r %s\n" % (index, name, raw, float(sig.phys_value), named))
    return 0


if __name__ == "__main__":
    sys.exit(main())
