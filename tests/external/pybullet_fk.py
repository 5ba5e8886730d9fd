"""PyBullet's forward kinematics of a URDF arm: the world pose of every link for each of a list
of joint configurations.

Usage: pybullet_fk.py ARM.urdf CONFIGS.json
CONFIGS.json: {"configurations": [{"joint name": value, ...}, ...]}
Prints {"poses": [{"link name": [x, y, z, qx, qy, qz, qw], ...}, ...]}, one entry per
configuration: the link frames as the URDF defines them (not the inertial frames), the base fixed
at the origin. Exit 1 when the file does not load or a joint name is unknown.
"""
import json
import sys

import pybullet as p

p.connect(p.DIRECT)
try:
    body = p.loadURDF(sys.argv[1], useFixedBase=True, flags=p.URDF_USE_INERTIA_FROM_FILE)
except Exception as e:  # noqa: BLE001
    print(f"PyBullet could not load {sys.argv[1]}: {e}", file=sys.stderr)
    sys.exit(1)
with open(sys.argv[2]) as f:
    configurations = json.load(f)["configurations"]

joints = {}
links = {}
for j in range(p.getNumJoints(body)):
    info = p.getJointInfo(body, j)
    joints[info[1].decode()] = j
    links[info[12].decode()] = j

poses = []
for configuration in configurations:
    for name, value in configuration.items():
        if name not in joints:
            print(f"no joint {name!r}", file=sys.stderr)
            sys.exit(1)
        p.resetJointState(body, joints[name], value)
    pose = {}
    for name, j in links.items():
        state = p.getLinkState(body, j, computeForwardKinematics=True)
        pose[name] = list(state[4]) + list(state[5])
    poses.append(pose)
print("\n" + json.dumps({"poses": poses}))
