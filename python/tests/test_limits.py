"""Joint values outside the robot's joint limits, from Python as on the command line:
`fk` computes them and warns, `identifiability` and `identify` refuse them naming the row and
the column."""
import numpy as np
import pytest

import calbench


def test_identifiability_refuses_joint_values_outside_the_limits_as_the_cli_does(cli, tmp_path):
    # `calbench identifiability --poses-file` refuses a pose outside the joint limits naming
    # the line and the column; from Python the same poses were analysed without a word.
    rng = np.random.default_rng(3)
    q = rng.uniform(-30.0, 30.0, (12, 6))
    q[2, 0] = 500.0
    poses = tmp_path / "poses.csv"
    lines = ["q1,q2,q3,q4,q5,q6"] + [",".join(map(repr, row)) for row in q.tolist()]
    poses.write_text("\n".join(lines) + "\n")
    msg = cli("identifiability", "--robot", "irb2600", "--poses-file", poses, "--json",
              ok=False).stderr
    assert "line 4, column q1: 500 is outside the joint limits [-180, 180]" in msg
    robot = calbench.Robot.builtin("irb2600")
    with pytest.raises(calbench.SettingError,
                       match=r"^setting `q`: row 2, column q1: 500 is outside the joint "
                             r"limits \[-180, 180\]$"):
        calbench.identifiability(robot, q)
    q[2, 0] = np.nan
    with pytest.raises(calbench.SettingError, match=r"row 2, column q1: NaN is not a finite"):
        calbench.identifiability(robot, q.tolist())
    # Joint 5's limits of ±120°, kept in radians, are shown as the robot file gives them.
    q[2, 0], q[2, 4] = 0.0, 500.0
    msg = r"^setting `q`: row 2, column q5: 500 is outside the joint limits \[-120, 120\]$"
    with pytest.raises(calbench.SettingError, match=msg):
        calbench.identifiability(robot, q)
    q[2, 4] = 0.0
    # The same rows as identify's arrays are refused in the same words.
    q[2, 0] = 500.0
    with pytest.raises(calbench.SettingError, match=r"^setting `q`: row 2, column q1: 500 is outside"):
        calbench.identify(robot, q, np.zeros((12, 3)))
