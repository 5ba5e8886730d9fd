"""Replays an `iscene simulate --robot` trajectory in MuJoCo; prints one JSON object.

usage: mujoco_replay.py REPLAY.xml TRAJECTORY.csv TOOL_BODY

Each line of the CSV sets the model's joint positions (a free joint's seven components are the
columns `<joint>.x` .. `<joint>.qz`); MuJoCo's forward kinematics and collision detection then
say where the robot is and what it touches. The robot is the body tree of `robot_base`, and
what the hand holds (the line's `held` body) counts with it.

{"samples": n, "steps": [..], "arm_travel_rad": total joint motion of the arm,
 "deepest": {"depth_m", "time", "step", "robot_body", "scene_body"} (the robot or what it holds
 into the scene; null when nothing touches), "deepest_per_step": {"<step>": depth_m},
 "held_drift_m": the most a held object moved in the frame of TOOL_BODY from one line to the
 next while held, "held_samples": lines with something held, "part_drift_m": the most TOOL_BODY
 moved in the frame of a door or drawer from one line to the next while the hand moved it (a
 hinge or slide joint of the scene changing on both), "part_samples": such lines,
 "missing_joints": [...]}
"""
import csv
import json
import sys

import mujoco
import numpy as np


def main(xml, trajectory, tool_body):
    m = mujoco.MjModel.from_xml_path(xml)
    d = mujoco.MjData(m)
    with open(trajectory, newline="") as f:
        rows = list(csv.reader(f))
    header, rows = rows[0], rows[1:]
    columns = []
    missing = []
    for i, name in enumerate(header[3:], start=3):
        joint, _, component = name.partition(".")
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, joint)
        if jid < 0:
            missing.append(joint)
            continue
        offset = ["x", "y", "z", "qw", "qx", "qy", "qz"].index(component) if component else 0
        columns.append((i, int(m.jnt_qposadr[jid]) + offset))
    robot_root = m.body("robot_base").id
    tool = m.body(tool_body).id
    base_joints = {"robot_x", "robot_y", "robot_yaw"}
    arm_columns = [
        a for i, a in columns
        if header[i] not in base_joints
        and m.body_rootid[m.jnt_bodyid[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, header[i].partition(".")[0])]] == robot_root
    ]
    # The scene's own hinge and slide joints (doors and drawers): (CSV column, qpos address, body).
    part_columns = []
    for i, adr in columns:
        jid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, header[i].partition(".")[0])
        if (
            int(m.jnt_type[jid]) in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
            and m.body_rootid[m.jnt_bodyid[jid]] != robot_root
        ):
            part_columns.append((i, int(m.jnt_bodyid[jid])))
    part_drift, part_samples, last_parts, last_in_part = 0.0, 0, None, {}
    deepest, per_step = None, {}
    drift, held_samples, previous, travel, last_arm = 0.0, 0, None, 0.0, None
    steps = []
    for row in rows:
        time, step, held = float(row[0]), int(row[1]), row[2]
        if not steps or steps[-1] != step:
            steps.append(step)
        d.qpos[:] = m.qpos0
        for i, adr in columns:
            d.qpos[adr] = float(row[i])
        mujoco.mj_forward(m, d)
        arm = np.array([d.qpos[a] for a in arm_columns])
        if last_arm is not None:
            travel += float(np.abs(arm - last_arm).sum())
        last_arm = arm
        held_root = m.body(held).rootid if held else -1
        robot_side = lambda g: m.body_rootid[m.geom_bodyid[g]] in (robot_root, held_root)  # noqa: E731
        for c in d.contact[: d.ncon]:
            a, b = robot_side(c.geom1), robot_side(c.geom2)
            if a == b:
                continue
            depth = float(-c.dist)
            per_step[str(step)] = max(per_step.get(str(step), 0.0), depth)
            if deepest is None or depth > deepest["depth_m"]:
                ours, theirs = (c.geom1, c.geom2) if a else (c.geom2, c.geom1)
                deepest = {
                    "depth_m": round(depth, 5),
                    "time": time,
                    "step": step,
                    "robot_body": m.body(m.geom_bodyid[ours]).name,
                    "scene_body": m.body(m.geom_bodyid[theirs]).name,
                }
        parts = [float(row[i]) for i, _ in part_columns]
        moving = [
            body for k, (_, body) in enumerate(part_columns)
            if last_parts is not None and abs(parts[k] - last_parts[k]) > 1e-6
        ]
        in_part = {}
        for body in moving:
            in_part[body] = d.xmat[body].reshape(3, 3).T @ (d.xpos[tool] - d.xpos[body])
            if body in last_in_part:
                part_drift = max(part_drift, float(np.linalg.norm(in_part[body] - last_in_part[body])))
        part_samples += bool(moving)
        last_parts, last_in_part = parts, in_part
        if held:
            held_samples += 1
            body = m.body(held).id
            in_tool = d.xmat[tool].reshape(3, 3).T @ (d.xpos[body] - d.xpos[tool])
            if previous is not None and previous[0] == held:
                drift = max(drift, float(np.linalg.norm(in_tool - previous[1])))
            previous = (held, in_tool)
        else:
            previous = None
    print(json.dumps({
        "samples": len(rows),
        "steps": steps,
        "arm_travel_rad": round(travel, 3),
        "deepest": deepest,
        "deepest_per_step": {k: round(v, 5) for k, v in per_step.items()},
        "held_drift_m": drift,
        "held_samples": held_samples,
        "part_drift_m": part_drift,
        "part_samples": part_samples,
        "missing_joints": missing,
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
