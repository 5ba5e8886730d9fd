"""Loads a URDF or MJCF in MuJoCo and rests it for 2 s; prints one JSON object.

{"bodies": n, "joints": n, "start_overlaps": [[depth_m, body_a, body_b], ...] (deeper than 1 mm),
 "free_moved": {"<joint>": metres}, "limit_overlaps": [[joint, value, depth_m, a, b], ...] (new overlaps with a joint at a limit)}
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
    for j in range(m.njnt):
        if m.jnt_limited[j] and int(m.jnt_type[j]) in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            for value in m.jnt_range[j]:
                d.qpos[:] = m.qpos0
                d.qpos[m.jnt_qposadr[j]] = value
                mujoco.mj_forward(m, d)
                for depth, a, b in overlaps(m, d):
                    if not any((a, b) == (x[1], x[2]) for x in start):
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
