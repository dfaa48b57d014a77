#!/usr/bin/python3
"""Prints what python3-rosbag (Debian's, independent of the C++ library) reads from a bag, one
`key value` line each, for rosbag_drive_reader_test to compare with what WriteRosbag wrote:
  topic <name> <type> <count>
  cloud_fields <name:offset:datatype,...>      (first message of the PointCloud2 topic)
  cloud_point0 <x> <y> <z> <intensity> [time]  (repr of the float32 values as Python floats)
  cloud_stamp0 <sec> <nsec>
  imu_orientation_cov0 <first message's orientation_covariance[0]> <second's>
  fix0 <status> <lat> <lon> <alt> <cov0> <cov8> <cov_type>
  vel0 <frame_id> <x> <y> <z>
Usage: summarize_bag.py BAG
"""
import struct
import sys

import rosbag


def main():
    bag = rosbag.Bag(sys.argv[1])
    info = bag.get_type_and_topic_info()
    for name, t in sorted(info.topics.items()):
        print('topic', name, t.msg_type, t.message_count)
    seen = set()
    imu_cov = []
    for topic, msg, _ in bag.read_messages():
        kind = msg._type
        if kind == 'sensor_msgs/PointCloud2' and 'cloud' not in seen:
            seen.add('cloud')
            print('cloud_fields', ','.join('%s:%d:%d' % (f.name, f.offset, f.datatype)
                                           for f in msg.fields))
            n = len(msg.fields)
            print('cloud_point0', ' '.join(repr(v) for v in struct.unpack_from('<%df' % n, msg.data, 0)))
            print('cloud_stamp0', msg.header.stamp.secs, msg.header.stamp.nsecs)
        elif kind == 'sensor_msgs/Imu' and len(imu_cov) < 2:
            imu_cov.append(repr(msg.orientation_covariance[0]))
        elif kind == 'sensor_msgs/NavSatFix' and 'fix' not in seen:
            seen.add('fix')
            print('fix0', msg.status.status, repr(msg.latitude), repr(msg.longitude),
                  repr(msg.altitude), repr(msg.position_covariance[0]),
                  repr(msg.position_covariance[8]), msg.position_covariance_type)
        elif kind == 'geometry_msgs/TwistStamped' and 'vel' not in seen:
            seen.add('vel')
            print('vel0', msg.header.frame_id, repr(msg.twist.linear.x), repr(msg.twist.linear.y),
                  repr(msg.twist.linear.z))
    print('imu_orientation_cov0', ' '.join(imu_cov))


if __name__ == '__main__':
    main()
