// ros2msg schema texts of sensor_msgs/msg/Imu and sensor_msgs/msg/Temperature as rosbag2 writes them
// into MCAP (the message definition, then each dependency after a line of 80 '='), from
// ros2/common_interfaces and ros2/rcl_interfaces (builtin_interfaces/Time).
const sep = "\n" + "=".repeat(80) + "\n";
const header = "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id";
const time = "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec";
export const imu = [
  "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n" +
    "geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n" +
    "geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance",
  header, time,
  "MSG: geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1",
  "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z",
].join(sep);
export const temperature = ["std_msgs/Header header\nfloat64 temperature\nfloat64 variance", header, time].join(sep);
