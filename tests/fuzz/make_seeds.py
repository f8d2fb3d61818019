#!/usr/bin/python3
"""Writes the text seed corpora of the fuzz targets: one valid file per
recording file type for fuzz_recording (first byte selects the type, 6 is
uwb.csv.gz, 7 a site calibration file, 8 gnss.csv, 9 neighbours.csv) and console sessions for fuzz_console.
Usage: tests/fuzz/make_seeds.py CORPUS_DIR"""
import gzip
import os
import sys

UWB = ("t_s,anchor_id,range_m,tag_id,nlos,fp_power_dbm,rx_power_dbm\n"
       "0.1,1,5.0,0,0,-80,-79\n# comment\n0.2,2,7.25,0,1,,\n0.3,3,9.5,1,,-90.5,-85\n")
RECORDING = {
    0: "anchor_id,x_m,y_m,z_m\n1,0,0,2\n2,30,0,2\n3,30,30,2\n4,0,30,2\n",
    1: "tag_id,x_m,y_m,z_m\n0,0,0,1\n1,0.5,-0.2,1.1\n",
    2: UWB,
    3: "t_s,ax_mps2,ay_mps2,az_mps2,gx_radps,gy_radps,gz_radps\n0.0,0.1,0,9.8,0,0,0.01\r\n0.004,0.1,0,9.8,0,0,0.01\r\n",
    4: "t_s,x_m,y_m,z_m,qw,qx,qy,qz\n0.0,5,5,0,1,0,0,0\n0.1,5.1,5,0,0.7071,0,0,0.7071\n",
    5: "name = fuzz\nplatform = air\ngravity_mps2 = 9.81\nuwb_sigma_m = 0.1\nbad line\n",
    7: ("# uwbnav range calibration v1\nsite_sigma_m = 0.0159\nsite_crc32 = 0xaf12d0c8\nmethod = truth\n"
        "anchor_id,tag_id,offset_m,sigma_m\n3,0,0.0727,0.0159\n5,0,0.0388,0.0144\n"),
    8: ("t_s,x_m,y_m,z_m,sx_m,sy_m,sz_m,fix,num_sv,latency_s,vx_mps,vy_mps,vz_mps,sv_mps\n"
        "1.0,5,5,1.5,0.8,0.8,1.6,2,12,0.08,1.5,0,0,0.05\n1.2,,,,,,,0,0,,,,,\n"
        "1.4,5.3,5,1.5,1.6,1.6,3.2,1,6,0.12,1.5,0.1,0,0.1\n1.6,5.6,5.1,1.4,0.8,0.8,1.6,2,11,,,,,\n"),
    9: ("t_s,vehicle_id,x_m,y_m,z_m,pxx_m2,pxy_m2,pxz_m2,pyy_m2,pyz_m2,pzz_m2,latency_s,vx_mps,vy_mps,vz_mps,coop\n"
        "1.0,32769,15,5,1.2,0.01,0.002,0,0.0225,0,0.04,0.05,5,0,0,0\n1.05,32770,-10,5.3,1.3,0.04,0,0,0.01,0,0.09,0.03,,,,1\n"
        "1.1,32769,15.5,5,1.2,0.01,0.002,0,0.0225,0,0.04,,5,0.1,0,\n"),
}
CONSOLE = [
    "help\r", "status\r\nstats\r\nanchors\r\n", "param list\rparam get gate.policy\rparam set gate.policy 2\r",
    "param save\rparam load\rparam reset\r", "stream pos 50\r\r\rstream off\r", "ekf -v\r", "log level debug\r",
    "reset filter\rreset stats\r", "history\r!!\r!1\r", "echo off\recho on\r", "cal\rversion\r",
    "abc\x7f\x7f\x03\x1b[A\x1b[B\r", "x" * 200 + "\r", "\x00\x01\xff\r",
]


def main():
    d = sys.argv[1]
    for target in ("fuzz_recording", "fuzz_console"):
        os.makedirs(os.path.join(d, target), exist_ok=True)
    for sel, text in RECORDING.items():
        with open(os.path.join(d, "fuzz_recording", f"type{sel}"), "wb") as f:
            f.write(bytes([sel]) + text.encode())
    with open(os.path.join(d, "fuzz_recording", "type6_gz"), "wb") as f:
        f.write(bytes([6]) + gzip.compress(UWB.encode(), mtime=0))
    for i, text in enumerate(CONSOLE):
        with open(os.path.join(d, "fuzz_console", f"session{i:02d}"), "wb") as f:
            f.write(text.encode("latin-1"))


if __name__ == "__main__":
    main()
