"""vehicle_imu of pyulog's sample_log_small.ulg as pyulog reads it: per multi_id and sample,
timestamp_sample, the integration periods and the mean rates delta / dt (gyro rad/s,
accelerometer m/s^2). Run with pyulog on PYTHONPATH (PX4/pyulog at the commit PROVENANCE.md names):
    PYTHONPATH=/path/to/pyulog python3 make_reference.py LOG > vehicle_imu_reference.csv
"""
import sys

from pyulog import ULog

log = ULog(sys.argv[1], ["vehicle_imu"])
print("multi_id,timestamp_sample_us,delta_angle_dt_us,delta_velocity_dt_us,"
      "gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z,gyro_device_id,accel_device_id")
for d in sorted(log.data_list, key=lambda d: d.multi_id):
    v = d.data
    for i in range(len(v["timestamp"])):
        da, dv = v["delta_angle_dt"][i] * 1e-6, v["delta_velocity_dt"][i] * 1e-6
        rates = [repr(float(v[f"delta_angle[{a}]"][i]) / da) for a in range(3)]
        accels = [repr(float(v[f"delta_velocity[{a}]"][i]) / dv) for a in range(3)]
        print(",".join([str(d.multi_id), str(v["timestamp_sample"][i]), str(v["delta_angle_dt"][i]),
                        str(v["delta_velocity_dt"][i])] + rates + accels +
                       [str(v["gyro_device_id"][i]), str(v["accel_device_id"][i])]))
