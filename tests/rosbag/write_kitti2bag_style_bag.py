#!/usr/bin/python3
"""Writes a small ROS 1 bag the way kitti2bag does, with Debian's python3-rosbag (an independent
writer for rosbag_drive_reader_test): /kitti/velo/pointcloud (x y z i float32, no time field,
frame velo_link), /kitti/oxts/imu (orientation from roll/pitch/yaw, covariances left 0),
/kitti/oxts/gps/fix (STATUS_FIX, COVARIANCE_TYPE_UNKNOWN), /kitti/oxts/gps/vel (forward/left/up
in the body frame, frame imu_link) and an unrelated /tf_static-like std_msgs/String topic.

The values follow formulas that the C++ test recomputes (see KittiStyleExpected there):
  scan s (0..4) at T0 + 0.1 s + 0.1 s * s, point k (0..N-1):
      a = 2 pi k / N, x = (10 + s) cos(a), y = (10 + s) sin(a), z = 0.01 k - 1, i = k / N
  IMU/GNSS/velocity message m (0..9) at T0 + 0.1 s * m:
      roll = 0.01 m, pitch = -0.02 m, yaw = 0.3 + 0.05 m
      accel = (0.1 m, -0.2, 9.81), gyro = (0.001 m, 0.002, -0.003 m)
      lat = 49 + 1e-6 m, lon = 8.4 + 2e-6 m, alt = 114 + 0.1 m (message 5: NaN latitude)
      vel = (5 + 0.1 m, 0.2, -0.05)
Usage: write_kitti2bag_style_bag.py OUT.bag
"""
import math
import struct
import sys

import genpy
import rosbag
from geometry_msgs.msg import TwistStamped
from sensor_msgs.msg import Imu, NavSatFix, NavSatStatus, PointCloud2, PointField
from std_msgs.msg import Header, String

T0_SEC = 1317000000
N_POINTS = 1000
N_SCANS = 5
N_OXTS = 10


def stamp(sec_offset_ns):
    ns = T0_SEC * 1000000000 + sec_offset_ns
    return genpy.Time(ns // 1000000000, ns % 1000000000)


def quaternion_from_euler(roll, pitch, yaw):
    """tf.transformations.quaternion_from_euler(roll, pitch, yaw) ('sxyz'): Rz(yaw) Ry(pitch) Rx(roll);
    returns x, y, z, w."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy)


def main():
    out = sys.argv[1]
    with rosbag.Bag(out, 'w') as bag:
        bag.write('/tf_static', String(data='velo_link -> imu_link'), t=stamp(0))
        for m in range(N_OXTS):
            t = stamp(100000000 * m)
            roll, pitch, yaw = 0.01 * m, -0.02 * m, 0.3 + 0.05 * m
            imu = Imu()
            imu.header = Header(seq=m, stamp=t, frame_id='imu_link')
            q = quaternion_from_euler(roll, pitch, yaw)
            imu.orientation.x, imu.orientation.y, imu.orientation.z, imu.orientation.w = q
            imu.linear_acceleration.x = 0.1 * m
            imu.linear_acceleration.y = -0.2
            imu.linear_acceleration.z = 9.81
            imu.angular_velocity.x = 0.001 * m
            imu.angular_velocity.y = 0.002
            imu.angular_velocity.z = -0.003 * m
            bag.write('/kitti/oxts/imu', imu, t=t)

            fix = NavSatFix()
            fix.header = Header(seq=m, stamp=t, frame_id='imu_link')
            fix.status.status = NavSatStatus.STATUS_FIX
            fix.status.service = NavSatStatus.SERVICE_GPS
            fix.latitude = float('nan') if m == 5 else 49.0 + 1e-6 * m
            fix.longitude = 8.4 + 2e-6 * m
            fix.altitude = 114.0 + 0.1 * m
            fix.position_covariance_type = NavSatFix.COVARIANCE_TYPE_UNKNOWN
            bag.write('/kitti/oxts/gps/fix', fix, t=t)

            vel = TwistStamped()
            vel.header = Header(seq=m, stamp=t, frame_id='imu_link')
            vel.twist.linear.x = 5.0 + 0.1 * m
            vel.twist.linear.y = 0.2
            vel.twist.linear.z = -0.05
            bag.write('/kitti/oxts/gps/vel', vel, t=t)

        fields = [PointField('x', 0, PointField.FLOAT32, 1),
                  PointField('y', 4, PointField.FLOAT32, 1),
                  PointField('z', 8, PointField.FLOAT32, 1),
                  PointField('i', 12, PointField.FLOAT32, 1)]
        for s in range(N_SCANS):
            t = stamp(100000000 + 100000000 * s)
            data = bytearray()
            for k in range(N_POINTS):
                a = 2.0 * math.pi * k / N_POINTS
                data += struct.pack('<ffff', (10.0 + s) * math.cos(a), (10.0 + s) * math.sin(a),
                                    0.01 * k - 1.0, k / N_POINTS)
            cloud = PointCloud2(header=Header(seq=s, stamp=t, frame_id='velo_link'), height=1,
                                width=N_POINTS, fields=fields, is_bigendian=False, point_step=16,
                                row_step=16 * N_POINTS, data=bytes(data), is_dense=True)
            bag.write('/kitti/velo/pointcloud', cloud, t=t)


if __name__ == '__main__':
    main()
