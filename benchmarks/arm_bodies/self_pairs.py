"""How often the robot file's self-collision pairs, and the two pairs it leaves out, come under the margin (issue 41).

Draws ``--postures`` uniform postures over the joint limits (seed 0), carries the default camera and bracket
(``robot.cell.DEFAULT_CARRIED``) and prints: the share of postures at which any listed pair (``self_collision``
of the robot file) is closer than ``--margin`` mm, the five pairs that bite most, and for the pairs left out on
purpose besides the adjacent links (link 2 against the base, link 3 against link 1) their share under the
margin, their least clearance and their clearance at all axes 0.

Usage (from the repository root, in the project's venv):
    python benchmarks/arm_bodies/self_pairs.py [--robot IRB1400 | FILE.yaml] [--postures 20000] [--margin 30]
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from handeye.robot.cell import DEFAULT_CARRIED
from handeye.robot.clearance import CellGuard
from handeye.robot.kinematics import RobotModel, load_robot

LEFT_OUT = (("link 2", "base"), ("link 3", "link 1"))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="IRB1400", help="a robot name or a robot file")
    parser.add_argument("--postures", type=int, default=20000)
    parser.add_argument("--margin", type=float, default=30.0)
    args = parser.parse_args(argv)
    robot = load_robot(args.robot)
    coupling = [[3, 2, -1.0]]
    every = RobotModel.from_dh("check", robot.dh, coupling, robot.joint_limits_deg, robot.max_speed_deg_s, robot.bodies,
                               robot.link_bodies, tuple(robot.self_pairs) + LEFT_OUT)
    guard = CellGuard(every, [], DEFAULT_CARRIED, margin_mm=args.margin)
    low, high = robot.joint_limits_deg.T
    joints = np.random.default_rng(0).uniform(low, high, (args.postures, robot.dof))
    pairs = guard._evaluate(joints)[5]  # (n, L): each pair's clearance
    home = guard._evaluate(np.zeros((1, robot.dof)))[5][0]
    labels = [tuple(label) for label in guard.self_check.labels]
    out = [i for i, label in enumerate(labels) if label in LEFT_OUT or label[::-1] in LEFT_OUT]
    listed = [i for i in range(len(labels)) if i not in out]
    print(f"{args.postures} postures, {args.margin:g} mm: the listed pairs refuse "
          f"{100 * np.mean(pairs[:, listed].min(axis=1) < args.margin):.1f} %")
    worst = sorted(listed, key=lambda i: -np.mean(pairs[:, i] < args.margin))[:5]
    print("  most often: " + "; ".join(f"{' against '.join(labels[i])} {100 * np.mean(pairs[:, i] < args.margin):.1f} %"
                                       for i in worst))
    for i in out:
        print(f"  left out: {' against '.join(labels[i])}: under the margin at {100 * np.mean(pairs[:, i] < args.margin):.1f} %"
              f", least {pairs[:, i].min():.0f} mm, {home[i]:.0f} mm at all axes 0")
    return 0


if __name__ == "__main__":
    sys.exit(main())
