"""Ctrl-C during a call is Python's KeyboardInterrupt, whatever call builds the first numpy
array of the process."""
import subprocess
import sys

SCRIPT = """
import os, signal, sys, threading
import calbench
robot = calbench.Robot.builtin("irb2600")
# A process started in the background by a shell without job control inherits SIGINT
# ignored, and Python then installs no handler: Ctrl-C as a terminal delivers it needs one.
signal.signal(signal.SIGINT, signal.default_int_handler)
threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
try:
    calbench.identify(robot, data=sys.argv[1], method="pso",
                      options={"iterations": int(sys.argv[2])}, allow_worse=True)
    print("finished before the interrupt")
except BaseException as e:
    print(type(e).__module__, type(e).__name__)
"""


def test_ctrl_c_during_the_first_identify_is_a_keyboard_interrupt(tmp_path, cli, root):
    # The first numpy array the process builds is identify's result: numpy's C API had been
    # loaded there, running Python code where the pending Ctrl-C raised, and the numpy crate
    # panicked (pyo3_runtime PanicException).
    cli("simulate", root / "scenarios" / "ci-guard.toml", "--out", tmp_path / "sim")
    data = tmp_path / "sim" / "measurements.csv"
    for iterations in (2000, 20000, 200000):
        r = subprocess.run([sys.executable, "-c", SCRIPT, str(data), str(iterations)],
                           capture_output=True, text=True, timeout=600)
        if "finished before the interrupt" not in r.stdout:
            break
    assert r.stdout.strip() == "builtins KeyboardInterrupt", r.stdout + r.stderr
