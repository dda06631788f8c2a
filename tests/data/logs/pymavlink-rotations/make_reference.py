#!/usr/bin/env python3
"""Reference numbers for ArduPilot's board rotations (AHRS_ORIENTATION), from pymavlink's rotmat.

For every rotation id pymavlink knows, the vector (1, 2, 3) rotated by the rotation
(Vector3.rotate_by_id: body from sensor) and by its inverse (rotate_by_inverse_id: sensor from
body, what Tools/scripts/tempcal_IMU.py applies to logged IMU values), printed with repr().

Run with pymavlink's rotmat.py on the module path (it imports only `math`):
    PYTHONPATH=/tmp/pymavrot python3 make_reference.py > rotations_reference.txt
"""
import rotmat

v = rotmat.Vector3(1.0, 2.0, 3.0)
print("# id name body_from_sensor(1,2,3) sensor_from_body(1,2,3)")
for rot_id, r in enumerate(rotmat.rotations):
    b = v.rotate_by_id(rot_id)
    s = v.rotate_by_inverse_id(rot_id)
    print(rot_id, r.name, repr(b.x), repr(b.y), repr(b.z), repr(s.x), repr(s.y), repr(s.z))
