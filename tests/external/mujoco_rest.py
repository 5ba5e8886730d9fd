"""Loads a URDF or MJCF in MuJoCo and rests it for 2 s; prints one JSON object.

{"bodies": n, "joints": n, "start_overlaps": [[depth_m, body_a, body_b], ...] (deeper than 1 mm),
 "free_moved": {"<joint>": metres}, "limit_overlaps": [[joint, value, depth_m, a, b], ...] (new overlaps with a joint at a limit that
 opening the other moving part involved does not clear)}
Exit code 0 when the file loads; a load failure prints the error and exits 1.
"""
import json
import sys

import mujoco
import numpy as np


def overlaps(m, d):
    out = []
    for i in range(d.ncon):
        c = d.contact[i]
        if c.dist < -0.001:
            a = m.body(m.geom_bodyid[c.geom1]).name
            b = m.body(m.geom_bodyid[c.geom2]).name
            out.append([round(float(-c.dist), 4), a, b])
    return sorted(set(map(tuple, out)), reverse=True)


def limited_joints(m):
    return [j for j in range(m.njnt)
            if m.jnt_limited[j] and int(m.jnt_type[j]) in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))]


def pose_with(m, d, values):
    d.qpos[:] = m.qpos0
    for j, value in values:
        d.qpos[m.jnt_qposadr[j]] = value
    mujoco.mj_forward(m, d)


def cleared_by_opening(m, d, j, value, a, b):
    """Whether the overlap of bodies a and b with joint j at value goes when a moving part it
    meets is opened too: a dishwasher's rack slides out through where its closed door is, and in
    use the door is opened first (in a simulation the closed door stops the rack)."""
    for k in limited_joints(m):
        if k == j or m.body(m.jnt_bodyid[k]).name not in (a, b):
            continue
        for other in m.jnt_range[k]:
            if other == 0.0:
                continue
            pose_with(m, d, [(j, value), (k, other)])
            if not any((a, b) == (x[1], x[2]) for x in overlaps(m, d)):
                return True
    return False


def main(path):
    try:
        m = mujoco.MjModel.from_xml_path(path)
    except Exception as e:  # noqa: BLE001 - report any load failure as the test's message
        print(f"MuJoCo could not load {path}: {e}", file=sys.stderr)
        return 1
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    start = overlaps(m, d)
    limit_overlaps = []
    for j in limited_joints(m):
        for value in m.jnt_range[j]:
            pose_with(m, d, [(j, value)])
            new = [(depth, a, b) for depth, a, b in overlaps(m, d)
                   if not any((a, b) == (x[1], x[2]) for x in start)]
            for depth, a, b in new:
                if not cleared_by_opening(m, d, j, value, a, b):
                    limit_overlaps.append([m.joint(j).name, float(value), depth, a, b])
    mujoco.mj_resetData(m, d)
    free = [j for j in range(m.njnt) if int(m.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE)]
    q0 = {j: d.qpos[m.jnt_qposadr[j]:m.jnt_qposadr[j] + 3].copy() for j in free}
    for _ in range(int(round(2.0 / m.opt.timestep))):
        mujoco.mj_step(m, d)
    moved = {
        m.joint(j).name: float(np.linalg.norm(d.qpos[m.jnt_qposadr[j]:m.jnt_qposadr[j] + 3] - q0[j]))
        for j in free
    }
    print(json.dumps({"bodies": m.nbody, "joints": m.njnt, "start_overlaps": start,
                      "free_moved": moved, "limit_overlaps": limit_overlaps}))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
