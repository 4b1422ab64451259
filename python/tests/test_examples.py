"""examples/python/ run as a user runs them: each exits 0 and prints what it
demonstrates (the control loop checks its own physics: PASS)."""
import os
import subprocess
import sys

from conftest import ROOT

EX = os.path.join(ROOT, "examples", "python")


def run(*args, cwd=None):
    p = subprocess.run([sys.executable, *args], capture_output=True, text=True, cwd=cwd)
    assert p.returncode == 0, p.stdout + p.stderr
    return p.stdout


def test_control_loop_100hz():
    out = run(os.path.join(EX, "control_loop_100hz.py"))
    assert out.rstrip().endswith("PASS")


def test_capture_run_example(tmp_path):
    png = tmp_path / "force.png"
    # a short piece of the handrail capture (0.3 s: the fingers have touched, no verdict yet)
    out = run(os.path.join(EX, "capture_run.py"), "--set", "simulation.duration=0.3", "-o", str(png))
    assert "verdict     unresolved" in out and "force profile" in out
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
