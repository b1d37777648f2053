"""notebook/tools/damping_study.py: the iterative correction moves each leg's command by the error's low harmonics."""
import importlib.util
from pathlib import Path

import numpy as np
import pytest

from cyberdog.config import RobotConfig
from cyberdog.core import kinematics as kin
from cyberdog.core.foot_offsets import FootOffsetPath
from cyberdog.core.kinematics import standing_joint_angles

ROOT = Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("damping_study", ROOT / "notebook" / "tools" / "damping_study.py")
tool = importlib.util.module_from_spec(spec)
spec.loader.exec_module(tool)


def test_the_correction_moves_the_command_by_the_gain_times_the_errors_low_harmonics():
    robot, n = RobotConfig(), 40
    stand = standing_joint_angles(robot).reshape(4, 3)
    phase = np.arange(n) / n
    command = np.repeat(stand[:, None, :], n, axis=1)  # (4, n, 3): the commanded joint angles per phase
    command[:, :, 1] += 0.1 * np.sin(2 * np.pi * phase)[None, :]
    low = 0.01 * np.cos(2 * np.pi * 2 * phase)  # the 2nd harmonic: moved
    high = 0.01 * np.sin(2 * np.pi * 9 * phase)  # the 9th: beyond 4 harmonics, left alone
    error = np.zeros_like(command)
    error[:, :, 2] = low + high
    table = FootOffsetPath(np.zeros((4, n, 3)), 0.4)
    out = tool.corrected(table, command, error, robot, gain=0.5, harmonics=4)
    for leg in range(4):
        side = np.full(n, kin.LEFT_RIGHT[leg])
        feet = kin.foot_position(command[leg], robot, side=side) + out.offsets[leg]  # the new targets
        q = kin.inverse_kinematics(feet, robot, side=side)
        np.testing.assert_allclose(q[:, 2] - command[leg, :, 2], 0.5 * low, atol=1e-9)
        np.testing.assert_allclose(q[:, :2], command[leg, :, :2], atol=1e-9)


def test_the_touchdown_split_takes_the_bins_around_each_legs_first_contact():
    bins = 40
    contact = np.zeros((4, bins))
    contact[:, 20:] = 1.0  # every leg touches down at bin 20
    difference = np.zeros((4, bins, 3))
    difference[:, 20, :] = 3.0  # the torque differs at touchdown only
    at, rest = tool.touchdown_split(difference, contact)
    assert at == pytest.approx(np.sqrt(3.0)) and rest == 0.0  # one of the three bins around touchdown differs
    difference[:, 30, :] = 1.0  # and in mid-stance
    assert tool.touchdown_split(difference, contact)[1] > 0.0
