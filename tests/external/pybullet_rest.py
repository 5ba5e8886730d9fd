"""Rests a scene URDF in PyBullet for 2 s and prints one JSON object:
{"free": n, "free_moved": {"<link>": metres}, "free_tilt_deg": {"<link>": degrees},
 "free_friction": {"<link>": the lateral friction PyBullet read for it}}.

PyBullet welds `floating` joints to their parent, and the links of one URDF never collide with
each other (../shared/VALIDATORS.md). So each floating object (with what hangs from it) is
loaded as a URDF of its own, free, at its pose in the scene, and the rest of the scene as one
fixed URDF; then everything rests under gravity. Exit 1 when a file does not load. Run in a
subprocess: PyBullet segfaults on some files.
"""
import copy
import json
import math
import os
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy as np
import pybullet as p

REST_SECONDS = 2.0
STEP_S = 1.0 / 240.0


def rotation(rpy):
    """URDF's fixed-axis roll, pitch, yaw: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    r, q, y = rpy
    cr, sr, cq, sq, cy, sy = math.cos(r), math.sin(r), math.cos(q), math.sin(q), math.cos(y), math.sin(y)
    return np.array([
        [cy * cq, cy * sq * sr - sy * cr, cy * sq * cr + sy * sr],
        [sy * cq, sy * sq * sr + cy * cr, sy * sq * cr - cy * sr],
        [-sq, cq * sr, cq * cr],
    ])


def origin(element):
    """The 4x4 pose of an element's <origin> (identity when it has none)."""
    pose = np.eye(4)
    o = element.find("origin")
    if o is not None:
        pose[:3, :3] = rotation([float(v) for v in o.get("rpy", "0 0 0").split()])
        pose[:3, 3] = [float(v) for v in o.get("xyz", "0 0 0").split()]
    return pose


def quaternion(m):
    """x, y, z, w of a rotation matrix."""
    w = math.sqrt(max(0.0, 1.0 + m[0, 0] + m[1, 1] + m[2, 2])) / 2.0
    x = math.copysign(math.sqrt(max(0.0, 1.0 + m[0, 0] - m[1, 1] - m[2, 2])) / 2.0, m[2, 1] - m[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1.0 - m[0, 0] + m[1, 1] - m[2, 2])) / 2.0, m[0, 2] - m[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1.0 - m[0, 0] - m[1, 1] + m[2, 2])) / 2.0, m[1, 0] - m[0, 1])
    return [x, y, z, w]


def write_robot(name, links, joints, folder):
    """A URDF of the given link and joint elements; its path."""
    robot = ET.Element("robot", name=name)
    robot.extend(copy.deepcopy(links) + copy.deepcopy(joints))
    path = os.path.join(folder, f"{name}.urdf")
    ET.ElementTree(robot).write(path)
    return path


def load(path, **kwargs):
    try:
        return p.loadURDF(path, **kwargs)
    except Exception as e:  # noqa: BLE001 - report any load failure as the test's message
        print(f"PyBullet could not load {path}: {e}", file=sys.stderr)
        sys.exit(1)


def main(path):
    robot = ET.parse(path).getroot()
    here = os.path.dirname(os.path.abspath(path))
    for mesh in robot.iter("mesh"):
        mesh.set("filename", os.path.join(here, mesh.get("filename")))
    links = {link.get("name"): link for link in robot.findall("link")}
    joints = robot.findall("joint")
    joint_to = {j.find("child").get("link"): j for j in joints}
    below = {}
    for j in joints:
        below.setdefault(j.find("parent").get("link"), []).append(j.find("child").get("link"))
    root = next(name for name in links if name not in joint_to)

    # Each link's frame in the world with every joint at zero.
    world = {root: np.eye(4)}
    stack = [root]
    while stack:
        parent = stack.pop()
        for child in below.get(parent, []):
            world[child] = world[parent] @ origin(joint_to[child])
            stack.append(child)

    def subtree(name):
        out, stack = [], [name]
        while stack:
            n = stack.pop()
            out.append(n)
            stack.extend(below.get(n, []))
        return out

    p.connect(p.DIRECT)
    p.setGravity(0, 0, -9.81)
    p.setTimeStep(STEP_S)
    free = {}
    carried = set()
    with tempfile.TemporaryDirectory() as folder:
        for j in joints:
            if j.get("type") != "floating":
                continue
            name = j.find("child").get("link")
            names = subtree(name)
            carried.update(names)
            file = write_robot(name, [links[n] for n in names],
                               [joint_to[n] for n in names if n != name], folder)
            pose = world[name]
            free[name] = load(file, basePosition=pose[:3, 3].tolist(),
                              baseOrientation=quaternion(pose[:3, :3]), useFixedBase=False)
        fixed = [n for n in links if n not in carried]
        scene = write_robot("scene", [links[n] for n in fixed],
                            [joint_to[n] for n in fixed if n != root], folder)
        load(scene, useFixedBase=True)

        start = {n: p.getBasePositionAndOrientation(b) for n, b in free.items()}
        for _ in range(int(round(REST_SECONDS / STEP_S))):
            p.stepSimulation()
        moved, tilt = {}, {}
        friction = {n: p.getDynamicsInfo(b, -1)[1] for n, b in free.items()}
        for n, b in free.items():
            (x0, q0), (x1, q1) = start[n], p.getBasePositionAndOrientation(b)
            moved[n] = float(np.linalg.norm(np.subtract(x1, x0)))
            z0 = np.array(p.getMatrixFromQuaternion(q0)).reshape(3, 3)[:, 2]
            z1 = np.array(p.getMatrixFromQuaternion(q1)).reshape(3, 3)[:, 2]
            tilt[n] = math.degrees(math.acos(max(-1.0, min(1.0, float(z0 @ z1)))))
    # PyBullet's own warnings end without a newline: start the JSON on a line of its own.
    print("\n" + json.dumps({"free": len(free), "free_moved": moved, "free_tilt_deg": tilt,
                             "free_friction": friction}))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
