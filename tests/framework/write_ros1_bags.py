#!/usr/bin/python3
"""ROS 1 bags for driftlab's tests, written at test time by Debian's python3-rosbag and
python3-sensor-msgs (a writer independent of driftlab's reader, librosbag-storage + ros_messages).

  write_ros1_bags.py cases DIR       the bags below, each with known values
  write_ros1_bags.py from-csv CSV BAG  an IMU CSV of `driftlab simulate` (t_s, gyro*_dps, accel*_mps2,
                                     temp*_c) as /imuN/data (sensor_msgs/Imu, rad/s, m/s^2) and
                                     /imuN/temperature (sensor_msgs/Temperature) at t_s + 1.7e9 s

Exit code 77 when python3-rosbag or python3-sensor-msgs is missing (the tests skip).

Cases (10 Hz, message i at t = 100 + i/10 s unless said otherwise; gyro z = 0.001 i rad/s, accel z =
9.8 + 0.001 i m/s^2, gyro x, y and accel x, y = 0):
  disorder.bag (bz2)  /imu/data, 50 messages; stamps of 10 and 11 swapped, message 20 repeats the
                      stamp of 19 (1 sample earlier than the one before; 1 repeated stamp)
  two_imus.bag (lz4)  /imu0/data, /imu1/data (gyro z + 1), 50 each; /imu0/temperature
                      (sensor_msgs/Temperature, 30 + 0.1 i degC), /imu1/temp_c (std_msgs/Float64,
                      40 + 0.1 i degC), /cabin/temperature (sensor_msgs/Temperature, unpaired)
  gyro_not_provided.bag  /imu/data with angular_velocity_covariance[0] = -1 (no gyro)
  empty_stamps.bag    /imu/data with header stamps 0 (receive times used)
  wrong_md5.bag       /imu/data as sensor_msgs/Imu with another md5sum (another message version)
  nan.bag             /imu/data with gyro x NaN at message 5
"""
import csv
import math
import sys

try:
    import rosbag
    import rospy
    from sensor_msgs.msg import Imu, Temperature
    from std_msgs.msg import Float64
except ImportError as e:
    print(f"write_ros1_bags.py: {e}", file=sys.stderr)
    sys.exit(77)


def stamp(seconds):
    return rospy.Time.from_sec(seconds)


def imu(t, gz, az, gx=0.0):
    m = Imu()
    m.header.stamp = stamp(t)
    m.header.frame_id = "imu_link"
    m.orientation.w = 1.0
    m.angular_velocity.x, m.angular_velocity.z = gx, gz
    m.linear_acceleration.z = az
    m.angular_velocity_covariance[0] = m.linear_acceleration_covariance[0] = 1e-6
    return m


def temperature(t, degc):
    m = Temperature()
    m.header.stamp = stamp(t)
    m.temperature = degc
    return m


def cases(out):
    n = 50
    times = [100 + i / 10 for i in range(n)]
    with rosbag.Bag(f"{out}/disorder.bag", "w", compression="bz2") as b:
        order = list(range(n))
        order[10], order[11] = 11, 10
        for k, i in enumerate(order):
            t = times[19] if i == 20 else times[i]
            b.write("/imu/data", imu(t, 0.001 * i, 9.8 + 0.001 * i), stamp(times[k]))
    with rosbag.Bag(f"{out}/two_imus.bag", "w", compression="lz4") as b:
        for i, t in enumerate(times):
            b.write("/imu0/data", imu(t, 0.001 * i, 9.8 + 0.001 * i), stamp(t))
            b.write("/imu1/data", imu(t + 0.003, 1 + 0.001 * i, 9.8 + 0.001 * i), stamp(t + 0.003))
            b.write("/imu0/temperature", temperature(t, 30 + 0.1 * i), stamp(t))
            b.write("/imu1/temp_c", Float64(40 + 0.1 * i), stamp(t + 0.004))
            b.write("/cabin/temperature", temperature(t, 22.0), stamp(t))
    with rosbag.Bag(f"{out}/gyro_not_provided.bag", "w") as b:
        for i, t in enumerate(times):
            m = imu(t, 0.001 * i, 9.8 + 0.001 * i)
            m.angular_velocity_covariance[0] = -1
            b.write("/imu/data", m, stamp(t))
    with rosbag.Bag(f"{out}/empty_stamps.bag", "w") as b:
        for i, t in enumerate(times):
            m = imu(t, 0.001 * i, 9.8 + 0.001 * i)
            m.header.stamp = rospy.Time(0)
            b.write("/imu/data", m, stamp(t))
    with rosbag.Bag(f"{out}/wrong_md5.bag", "w") as b:
        for i, t in enumerate(times):
            m = imu(t, 0.001 * i, 9.8 + 0.001 * i)
            from io import BytesIO
            buf = BytesIO()
            m.serialize(buf)
            b.write("/imu/data", ("sensor_msgs/Imu", buf.getvalue(), "0123456789abcdef0123456789abcdef", Imu), stamp(t), raw=True)
    with rosbag.Bag(f"{out}/nan.bag", "w") as b:
        for i, t in enumerate(times):
            b.write("/imu/data", imu(t, 0.001 * i, 9.8 + 0.001 * i, math.nan if i == 5 else 0.0), stamp(t))


def from_csv(path, bag_path):
    deg = math.pi / 180
    epoch = 1700000000.0
    with open(path) as f, rosbag.Bag(bag_path, "w", compression="lz4") as b:
        for row in csv.DictReader(f):
            t = epoch + float(row["t_s"])
            for n, suffix in ((0, ""), (1, "1")):
                if f"gyro{suffix}_x_dps" not in row:
                    continue
                m = Imu()
                m.header.stamp = stamp(t)
                m.orientation.w = 1.0
                m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z = (
                    float(row[f"gyro{suffix}_{a}_dps"]) * deg for a in "xyz")
                m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z = (
                    float(row[f"accel{suffix}_{a}_mps2"]) for a in "xyz")
                b.write(f"/imu{n}/data", m, stamp(t))
                b.write(f"/imu{n}/temperature", temperature(t, float(row[f"temp{suffix}_c"])), stamp(t))


if __name__ == "__main__":
    if sys.argv[1] == "cases":
        cases(sys.argv[2])
    else:
        from_csv(sys.argv[2], sys.argv[3])
