#!/usr/bin/env python3
"""Reference numbers of an ArduPilot DataFlash log from pymavlink's DFReader (an independent reader).

Usage (pymavlink on PYTHONPATH, e.g. a checkout of github.com/ArduPilot/pymavlink with its
ardupilotmega dialect generated; see tests/data/logs/README.md):
    MAVLINK_DIALECT=ardupilotmega python3 dataflash_reference.py LOG.bin > reference.txt

Output, one fact per line (read by tests/framework/dataflash_test.cpp):
    type NAME COUNT FIRST_TIME_US LAST_TIME_US      every message type DFReader returned
    imu INSTANCE COUNT                              IMU messages per instance (I, or IMU/IMU2/IMU3)
    imu_first INSTANCE COLUMN VALUE                 TimeUS, GyrX..Z, AccX..Z, T of the first message
    imu_last INSTANCE COLUMN VALUE                  ... of the last one
    param NAME VALUE                                first logged value of the parameters a reader of
                                                    IMU drift needs (device ids, INS_TCAL*, CALTEMP,
                                                    AHRS_ORIENTATION)
Values are printed with repr(): the exact double DFReader holds.
"""
import re
import sys
from collections import OrderedDict

from pymavlink import DFReader

COLUMNS = ["TimeUS", "GyrX", "GyrY", "GyrZ", "AccX", "AccY", "AccZ", "T"]
PARAM = re.compile(r"^(INS_(GYR|ACC)\d?_ID|INS_TCAL\d_.*|INS_(GYR|ACC)\d_CALTEMP|AHRS_ORIENTATION)$")


def main(path):
    log = DFReader.DFReader_binary(path, zero_time_base=False)
    types = OrderedDict()
    imu = OrderedDict()
    params = OrderedDict()
    while True:
        m = log.recv_msg()
        if m is None:
            break
        name = m.get_type()
        time_us = getattr(m, "TimeUS", None)
        if time_us is None and hasattr(m, "TimeMS"):
            time_us = m.TimeMS * 1000
        entry = types.setdefault(name, [0, time_us, time_us])
        entry[0] += 1
        entry[2] = time_us
        if name in ("IMU", "IMU2", "IMU3"):
            instance = getattr(m, "I", {"IMU": 0, "IMU2": 1, "IMU3": 2}[name])
            row = imu.setdefault(instance, [0, None, None])
            values = [getattr(m, c) for c in COLUMNS]
            row[0] += 1
            row[1] = row[1] or values
            row[2] = values
        if name == "PARM" and PARAM.match(m.Name) and m.Name not in params:
            params[m.Name] = m.Value
    for name, (count, first, last) in types.items():
        print("type %s %d %s %s" % (name, count, first, last))
    for instance, (count, first, last) in sorted(imu.items()):
        print("imu %d %d" % (instance, count))
        for column, value in zip(COLUMNS, first):
            print("imu_first %d %s %r" % (instance, column, value))
        for column, value in zip(COLUMNS, last):
            print("imu_last %d %s %r" % (instance, column, value))
    for name, value in params.items():
        print("param %s %r" % (name, value))


if __name__ == "__main__":
    main(sys.argv[1])
