#!/usr/bin/env python3
"""Independent oracle for urdf-dh's MJCF reader: MuJoCo's own forward kinematics.

For every MJCF chain of fixtures/mjcf/chains.json and ../shared/formats/manifest.json, in both DH conventions, runs
`urdf-dh extract FILE --base B --tip T --convention C --format json` and compares the table's
forward kinematics (base * prod(row transforms) * tool, joint values = MuJoCo qpos, mimic rows
driven by their driver), and likewise the product of exponentials of `--format poe`, with MuJoCo's `mj_kinematics` (data.xpos / data.xquat of the tip body in
the base body's frame) at random qpos: joints with a range inside it, others in [-pi, pi]
(hinge) or [-0.5, 0.5] m (slide). Passes at 1e-9 m and 1e-9 rad.

Usage: python tests/formats/mjcf_oracle.py [--bin target/release/urdf-dh]
       [--formats ../shared/formats] [--samples 200] [--seed 1]
Prints one line per chain and form (standard, modified, poe), then 'N passed, N failed'; exits 1 on a failure,
0 otherwise (the real models skipped, saying so, when ../shared/formats is absent).
"""
import argparse
import json
import math
import os
import subprocess
import sys

import mujoco
import numpy as np

LINEAR = 1e-9  # metres
ANGULAR = 1e-9  # radians


def rot(axis, angle):
    c, s = math.cos(angle), math.sin(angle)
    if axis == "x":
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == "y":
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def hom(r=None, p=None):
    t = np.eye(4)
    if r is not None:
        t[:3, :3] = r
    if p is not None:
        t[:3, 3] = p
    return t


def xyz_rpy(pose):
    """URDF-style pose: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    (x, y, z), (r, p, w) = pose["xyz"], pose["rpy"]
    return hom(rot("z", w) @ rot("y", p) @ rot("x", r), [x, y, z])


def dh_fk(table, q):
    t = xyz_rpy(table["base"])
    modified = table["convention"] == "modified"
    for row, v in zip(table["joints"], q):
        theta, d = row["theta"], row["d"]
        if row["type"] == "prismatic":
            d += v
        else:
            theta += v
        rz, tz = hom(rot("z", theta)), hom(p=[0, 0, d])
        tx, rx = hom(p=[row["a"], 0, 0]), hom(rot("x", row["alpha"]))
        t = t @ (rx @ tx @ rz @ tz if modified else rz @ tz @ tx @ rx)
    return t @ xyz_rpy(table["tool"])


def poe_fk(doc, q):
    """exp([S1] q1) ... exp([Sn] qn) M (Modern Robotics eq. 4.14), each exponential by eq. 3.88."""
    t = np.eye(4)
    for joint, theta in zip(doc["joints"], q):
        s = np.array(joint["screw"], dtype=float)
        w, v = s[:3], s[3:]
        e = np.eye(4)
        if not w.any():
            e[:3, 3] = v * theta
        else:
            k = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
            e[:3, :3] = np.eye(3) + math.sin(theta) * k + (1 - math.cos(theta)) * k @ k
            e[:3, 3] = (np.eye(3) * theta + (1 - math.cos(theta)) * k + (theta - math.sin(theta)) * k @ k) @ v
        t = t @ e
    return t @ np.array(doc["home"], dtype=float)


def body_pose(data, body):
    r = np.zeros(9)
    mujoco.mju_quat2Mat(r, data.xquat[body])
    return hom(r.reshape(3, 3), data.xpos[body])


def angle_between(a, b):
    r = a[:3, :3].T @ b[:3, :3]
    s = 0.5 * math.sqrt((r[2, 1] - r[1, 2]) ** 2 + (r[0, 2] - r[2, 0]) ** 2 + (r[1, 0] - r[0, 1]) ** 2)
    c = 0.5 * (np.trace(r) - 1.0)
    return math.atan2(s, c)


def check(binary, folder, entry, convention, samples, rng):
    path = os.path.join(folder, entry["file"])
    cmd = [binary, "extract", path, "--base", entry["base"], "--tip", entry["tip"]]
    cmd += ["--format", "poe"] if convention == "poe" else ["--convention", convention, "--format", "json"]
    run = subprocess.run(cmd, capture_output=True, text=True)
    if run.returncode != 0:
        return False, f"extract exited {run.returncode}: {run.stderr.strip()}"
    table = json.loads(run.stdout)
    if table["length_unit"] != "m" or table["angle_unit"] != "rad":
        return False, f"expected units m and rad, found {table['length_unit']} and {table['angle_unit']}"
    model = mujoco.MjModel.from_xml_path(path)
    data = mujoco.MjData(model)
    base = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, entry["base"])
    tip = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, entry["tip"])
    rows = table["joints"]
    adr = {}
    for row in rows:
        j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, row["name"])
        if j < 0:
            return False, f"row '{row['name']}' is no joint of the model"
        adr[row["name"]] = model.jnt_qposadr[j]
    worst_p = worst_r = 0.0
    for k in range(samples):
        qpos = model.qpos0.copy()
        for j in range(model.njnt):
            if model.jnt_type[j] not in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
                continue
            if model.jnt_limited[j]:
                lo, hi = model.jnt_range[j]
            elif model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE:
                lo, hi = -math.pi, math.pi
            else:
                lo, hi = -0.5, 0.5
            qpos[model.jnt_qposadr[j]] = 0.0 if k == 0 else rng.uniform(lo, hi)
        for row in rows:  # mimic rows follow their driver, as the table says
            m = row.get("mimic")
            if m and m["joint"] in adr:
                qpos[adr[row["name"]]] = m["multiplier"] * qpos[adr[m["joint"]]] + m["offset"]
        data.qpos[:] = qpos
        mujoco.mj_kinematics(model, data)
        want = np.linalg.inv(body_pose(data, base)) @ body_pose(data, tip)
        values = [qpos[adr[r["name"]]] for r in rows]
        got = poe_fk(table, values) if convention == "poe" else dh_fk(table, values)
        worst_p = max(worst_p, float(np.linalg.norm(got[:3, 3] - want[:3, 3])))
        worst_r = max(worst_r, angle_between(got, want))
    ok = worst_p <= LINEAR and worst_r <= ANGULAR
    return ok, f"{len(rows)} rows, {samples} samples, worst {worst_p:.1e} m, {worst_r:.1e} rad"


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.dirname(os.path.dirname(here))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default=os.path.join(root, "target", "release", "urdf-dh"))
    ap.add_argument("--formats", default=os.path.join(root, "..", "shared", "formats"))
    ap.add_argument("--samples", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    entries = []
    fixtures = os.path.join(root, "fixtures", "mjcf")
    manifest = os.path.join(args.formats, "manifest.json")
    for folder, listing in ((fixtures, "chains.json"), (args.formats, "manifest.json")):
        path = os.path.join(folder, listing)
        if not os.path.isfile(path):
            print(f"mjcf_oracle: {path} not found; its chains are not checked", file=sys.stderr)
            continue
        with open(path) as f:
            entries += [(folder, e) for e in json.load(f)["models"] if e["format"] == "mjcf"]
    rng = np.random.default_rng(args.seed)
    passed = failed = 0
    print(f"mujoco {mujoco.__version__}, tolerances {LINEAR:g} m, {ANGULAR:g} rad")
    for folder, entry in entries:
        for convention in ("standard", "modified", "poe"):
            try:
                ok, what = check(args.bin, folder, entry, convention, args.samples, rng)
            except Exception as e:  # a crash of one chain is its failure, not the run's
                ok, what = False, f"error: {e!r}"
            passed += ok
            failed += not ok
            print(f"{'ok  ' if ok else 'FAIL'} {entry['id']:<22} {convention:<9} {what}")
    print(f"{passed} passed, {failed} failed")
    if not os.path.isfile(manifest):
        print("mjcf_oracle: the real models were skipped: ../shared/formats is absent")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
