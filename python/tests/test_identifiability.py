"""`calbench.identifiability` for every instrument `calbench identifiability --poses-file`
reads, with the command line's numbers, and its instrument options refused where no kind
reads them."""
import json

import numpy as np
import pytest

import calbench


def poses(tmp_path, robot, n=60):
    """`n` joint vectors within the IRB 2600's limits (deg) and their pose list."""
    rng = np.random.default_rng(4)
    q = rng.uniform(-60.0, 60.0, (n, robot.joint_count))
    f = tmp_path / "poses.csv"
    header = ",".join(f"q{j + 1}" for j in range(robot.joint_count))
    np.savetxt(f, q, delimiter=",", header=header, comments="", fmt="%.17g")
    return q, f


@pytest.mark.parametrize("measure, options, flags", [
    ("position", {}, []),
    ("pose", {}, []),
    ("distance", {}, []),
    ("distance", {"between_poses": True}, ["--between-poses"]),
    ("plane", {"planes": 4}, ["--planes", "4"]),
    ("sphere", {"spheres": 2}, ["--spheres", "2"]),
    ("multi-target", {}, []),
])
def test_every_instrument_gives_the_command_lines_analysis(cli, tmp_path, measure, options,
                                                            flags):
    robot = calbench.Robot.builtin("irb2600")
    q, f = poses(tmp_path, robot)
    got = calbench.identifiability(robot, q, measure, **options)
    want = json.loads(cli("identifiability", "--robot", "irb2600", "--measure", measure,
                          "--poses-file", f, "--json", *flags).stdout)
    assert got.pop("parameters") == len(robot.parameter_names())
    assert got.keys() == want.keys()
    for key, value in want.items():
        assert got[key] == pytest.approx(value, rel=1e-12) if key == "condition_number" \
            else got[key] == value, key
    if measure not in ("position", "pose"):
        # A pivot, planes or spheres are unknowns; consecutive lengths and targets have none.
        assert got["measure"] == measure
        assert bool(got["instrument_unknowns"]) == (measure != "multi-target" and not options
                                                    .get("between_poses"))


def test_a_plane_touched_at_one_point_leaves_its_tilt_free():
    robot = calbench.Robot.builtin("irb2600")
    q = np.random.default_rng(3).uniform(-60, 60, (30, 6))
    got = calbench.identifiability(robot, q, "plane")
    assert got["undetermined_instrument_unknowns"] == []
    q[0::3] = q[0]  # the poses of plane 1 (every third) all at its first
    got = calbench.identifiability(robot, q, "plane")
    free = got["undetermined_instrument_unknowns"]
    assert len(free) == 2 and all(n.startswith("plane1_") for n in free), free


def test_instrument_options_are_refused_where_no_kind_reads_them():
    robot = calbench.Robot.builtin("irb2600")
    q = np.zeros((4, 6)) + np.arange(4)[:, None]
    for measure, options, says in [
        ("position", {"planes": 3}, "setting `planes`: is read only with measure=\"plane\""),
        ("plane", {"spheres": 2}, "setting `spheres`: is read only with measure=\"sphere\""),
        ("sphere", {"between_poses": True}, "`between_poses`: is read only with measure="),
        ("plane", {"planes": 0}, "setting `planes`: must be a whole number ≥ 1, got 0"),
        ("distance", {"between_poses": "yes"}, "setting `between_poses`: expected True"),
        ("tracker", {}, "setting `measure`: \"tracker\" is not a measure; allowed: position, "
                        "pose, distance"),
    ]:
        with pytest.raises(calbench.SettingError, match=says):
            calbench.identifiability(robot, q, measure, **options)


def test_more_planes_or_spheres_than_the_poses_fill_are_refused_naming_the_option(cli,
                                                                                 tmp_path):
    # 30 poses cannot give 31 planes 4 points each, nor 30 spheres 5: refused naming
    # `planes` and `spheres` (as the command line names --planes), where a `measurements`
    # nobody gave was named, with "plane 1 has 1 points".
    robot = calbench.Robot.builtin("irb2600")
    q, f = poses(tmp_path, robot, n=30)
    for kind, option, n, need in [("plane", "planes", 31, 4), ("sphere", "spheres", 30, 5)]:
        with pytest.raises(calbench.SettingError,
                           match=rf"^setting `{option}`: {kind} \d+ of {n} holds \d of the 30 "
                                 rf"poses, and each needs at least {need}: give more poses, or "
                                 rf"fewer {kind}s \(`?{option}`?\)$"):
            calbench.identifiability(robot, q, kind, **{option: n})
    msg = cli("identifiability", "--robot", "irb2600", "--measure", "plane", "--planes", "31",
              "--poses-file", f, ok=False).stderr
    assert "setting `--planes`: plane " in msg and "fewer planes (--planes)" in msg, msg
    # Enough poses a plane: analysed.
    assert calbench.identifiability(robot, q, "plane", planes=7)["rank"] > 0


def test_counts_and_poses_no_instrument_can_use_are_named_by_their_argument():
    # A plane count beyond a measurement file's had been named `measurement.planes` (a
    # study's key), and one pose between poses `data` ("no observations").
    robot = calbench.Robot.builtin("irb2600")
    q = np.zeros((30, 6)) + np.linspace(-20.0, 20.0, 30)[:, None]
    for measure, options, says in [
        ("plane", {"planes": 2**63}, "^setting `planes`: must be at most 1000"),
        ("sphere", {"spheres": 5000}, "^setting `spheres`: must be at most 1000"),
    ]:
        with pytest.raises(calbench.SettingError, match=says):
            calbench.identifiability(robot, q, measure, **options)
    with pytest.raises(calbench.SettingError,
                       match="^setting `q`: 1 pose gives no distance reading: give more poses$"):
        calbench.identifiability(robot, q[:1], "distance", between_poses=True)
    with pytest.raises(calbench.SettingError, match="^setting `q`: distance 1 has 4 points"):
        calbench.identifiability(robot, q[:4], "distance")
