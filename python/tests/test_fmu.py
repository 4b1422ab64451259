"""capdyn fmu: a scenario as an FMI 2.0 co-simulation FMU (issue 20, docs/fmu.md),
checked with fmpy (pinned in python/requirements.txt).

The scenario: scenarios/space_gripper_irregular.toml (the Space Gripper closing
on an irregular prism, captured at 0.569 s), cut to 0.75 s, with the output
interval 2^-10 s: every communication point k 2^-10 and every step size are
then exact in binary, so that the importer's t + h is capdyn run's sample time
to the last bit and both take the same integrator steps. capdyn run samples
with simulation.sampling = "stop" (its steps end on the samples, as the FMU's
end on the communication points): with the default "interpolate" of the auto
stepper its samples would be interpolants between other steps."""
import ctypes
import os
import shutil
import subprocess
import sys
import zipfile

import h5py
import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, defaultCallbacks
from fmpy.validation import validate_fmu

from conftest import BIN, BUILD, run_cli, scenario

DT = 2.0 ** -10  # [s] communication step = capdyn run's output_dt
SETS = ["--set", f"simulation.output_dt={DT!r}", "--set", "simulation.duration=0.75",
        "--set", 'simulation.sampling="stop"']
SCEN = scenario("space_gripper_irregular.toml")


@pytest.fixture(scope="module")
def fmu_path(tmp_path_factory, capdyn_bin):
    d = tmp_path_factory.mktemp("fmu")
    path = str(d / "capture.fmu")
    out = run_cli("fmu", SCEN, "-o", path, "--param", "contact.mu=0.5", *SETS)
    assert "FMI 2.0 co-simulation FMU" in out
    return path


@pytest.fixture(scope="module")
def run_h5(tmp_path_factory, capdyn_bin):
    d = tmp_path_factory.mktemp("run")
    path = str(d / "run.h5")
    run_cli("run", "-q", SCEN, "-o", path, *SETS)
    return path


def vrs(md):
    return {v.name: v for v in md.modelVariables}


def test_fmu_validates_and_its_zip_is_sound(fmu_path):
    # fmpy's checks: the XML schema, names, value references, model structure
    assert validate_fmu(fmu_path) == []
    with zipfile.ZipFile(fmu_path) as z:
        assert z.testzip() is None  # every entry's CRC-32 (src/fmu/zip.c)
        names = set(z.namelist())
        info = z.getinfo("binaries/linux64/capdyn_fmu.so")
        assert info.compress_type == zipfile.ZIP_STORED
        assert (info.external_attr >> 16) & 0o777 == 0o755
    assert {"modelDescription.xml", "binaries/linux64/capdyn_fmu.so", "resources/scenario.toml",
            "resources/params.txt"} <= names
    md = read_model_description(fmu_path)
    cs = md.coSimulation
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate and cs.canHandleVariableCommunicationStepSize
    v = vrs(md)
    assert v["capture.verdict"].type == "Integer" and v["capture.verdict"].causality == "output"
    assert v["contact.mu"].causality == "parameter" and float(v["contact.mu"].start) == 0.5
    assert v["hand.f0_l0.tau"].causality == "input"


def object_slots(f):
    slots = f["contacts/slots"][:]
    names = lambda col: [n.decode() if isinstance(n, bytes) else n for n in slots[col]]
    a, b = names("body_a_name"), names("body_b_name")
    return [k for k in range(len(slots)) if a[k].split("/")[0] == "object" or b[k].split("/")[0] == "object"]


def test_zero_inputs_equal_capdyn_run_bit_for_bit(fmu_path, run_h5):
    """fmpy simulate with zero inputs = capdyn run at every communication point:
    bit-identical (tolerance 0), the same step sequence."""
    r = simulate_fmu(fmu_path, output_interval=DT)
    with h5py.File(run_h5, "r") as f:
        t = f["time"][:]
        np.testing.assert_array_equal(r["time"], t)
        obj, hand = f["systems/object"], f["systems/hand"]
        for k, c in enumerate("xyz"):
            np.testing.assert_array_equal(r[f"object.base.{c}"], obj["base_pos"][:, k])
            np.testing.assert_array_equal(r[f"object.base.v{c}"], obj["base_vel"][:, k])
            np.testing.assert_array_equal(r[f"object.base.w{c}"], obj["base_angvel"][:, k])
        for k, c in enumerate(["qw", "qx", "qy", "qz"]):
            np.testing.assert_array_equal(r[f"object.base.{c}"], obj["base_quat"][:, k])
        names = [n.decode() if isinstance(n, bytes) else n for n in hand.attrs["joint_names"]]
        for j, n in enumerate(names):
            np.testing.assert_array_equal(r[f"hand.{n}.q"], hand["q"][:, j])
            np.testing.assert_array_equal(r[f"hand.{n}.qd"], hand["qd"][:, j])
        ks = object_slots(f)
        assert ks, "the object has contact slots"
        fn = np.zeros(len(t))
        for k in ks:  # summed in slot order, as the FMU does
            fn = fn + f["contacts/fn"][:, k]
        np.testing.assert_array_equal(r["contact.fn_total"], fn)
        mode = f["contacts/mode"][:, ks]
        np.testing.assert_array_equal(r["contact.n_stick"], (mode == 1).sum(axis=1))
        np.testing.assert_array_equal(r["contact.n_slip"], (mode == 2).sum(axis=1))
        assert r["contact.n_stick"][-1] + r["contact.n_slip"][-1] > 0
        verdict = f.attrs["capture_verdict"]
        verdict = verdict.decode() if isinstance(verdict, bytes) else verdict
        assert verdict == "captured"
        # cd_verdict values: 0 unresolved, 1 captured, 2 escaped
        assert r["capture.verdict"][-1] == 1
        assert r["capture.time"][-1] == f.attrs["capture_t"]
        assert r["capture.verdict"][0] == 0 and r["capture.time"][0] == -1.0


class Logged:
    """An fmpy slave with a logger that keeps the messages."""

    def __init__(self, path):
        self.md = read_model_description(path)
        self.dir = extract(path)
        self.messages = []

        def log(env, name, status, cat, msg):
            self.messages.append((status, msg.decode()))

        self._cb = fmi2CallbackFunctions()
        self._cb.logger = fmi2CallbackLoggerTYPE(log)
        self._cb.allocateMemory = defaultCallbacks.allocateMemory
        self._cb.freeMemory = defaultCallbacks.freeMemory
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName="t")
        self.fmu.instantiate(callbacks=self._cb)
        self.v = vrs(self.md)
        self.out = [v.valueReference for v in self.md.modelVariables if v.causality == "output" and v.type == "Real"]
        self.iout = [v.valueReference for v in self.md.modelVariables if v.causality == "output" and v.type == "Integer"]

    def start(self):
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()

    def outputs(self):
        return self.fmu.getReal(self.out) + self.fmu.getInteger(self.iout)

    def steps(self, t, n, h=DT):
        rows = []
        for _ in range(n):
            self.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            t += h
            rows.append(self.outputs())
        return t, np.array(rows)

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.dir, ignore_errors=True)


def test_get_set_and_serialized_state_continue_bit_identical(fmu_path):
    """get state, simulate on, set state, simulate again: bit-identical; the same
    through serialize / deserialize; fmi2Reset gives the first run again."""
    s = Logged(fmu_path)
    try:
        s.start()
        first0 = s.outputs()
        t, _ = s.steps(0.0, 300)           # 0.29 s: the fingers touch the object
        state = s.fmu.getFMUstate()
        blob = s.fmu.serializeFMUstate(state)
        t1, a = s.steps(t, 320)            # to 0.605 s, through the capture (0.569 s)
        s.fmu.setFMUstate(state)
        t2, b = s.steps(t, 320)
        np.testing.assert_array_equal(a, b)
        state2 = s.fmu.deSerializeFMUstate(blob)
        s.fmu.setFMUstate(state2)
        _, c = s.steps(t, 320)
        np.testing.assert_array_equal(a, c)
        iv = len(s.out) + s.iout.index(s.v["capture.verdict"].valueReference)
        assert a[0][iv] == 0 and a[-1][iv] == 1  # the capture happens inside the restored span
        s.fmu.freeFMUstate(state)
        s.fmu.freeFMUstate(state2)
        # a longer communication step over the same span: the same physics,
        # other integrator steps (within the error control: rtol 1e-8)
        s.fmu.reset()
        s.start()
        np.testing.assert_array_equal(s.outputs(), first0)
        _, d = s.steps(0.0, 300)
        s.fmu.reset()
        s.start()
        _, e = s.steps(0.0, 30, h=10 * DT)
        np.testing.assert_allclose(e[-1][: len(s.out)], d[-1][: len(s.out)], rtol=0, atol=1e-6)
        assert not [m for m in s.messages if m[0] >= 3]
    finally:
        s.close()


def test_errors_reach_the_logger_and_fmi2Error(fmu_path):
    s = Logged(fmu_path)
    try:
        s.start()
        saved = s.fmu.getFMUstate()
        x0 = s.outputs()
        # a communication point that is not the FMU's time
        with pytest.raises(Exception):
            s.fmu.doStep(currentCommunicationPoint=0.5, communicationStepSize=DT)
        assert s.messages and s.messages[-1][0] == 3  # fmi2Error
        assert "currentCommunicationPoint 0.5 is not the FMU's time 0" in s.messages[-1][1]
        # after fmi2Error: the outputs still read (the last good state), and
        # fmi2SetFMUstate of an earlier state goes on from there
        assert s.outputs() == x0
        s.fmu.setFMUstate(saved)
        s.fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=DT)
        s.fmu.freeFMUstate(saved)
        # a parameter out of the loader's range: its message, naming the key
        s.fmu.reset()
        s.fmu.setReal([s.v["contact.mu"].valueReference], [-1.0])
        s.fmu.setupExperiment(startTime=0.0)
        s.fmu.enterInitializationMode()
        with pytest.raises(Exception):
            s.fmu.exitInitializationMode()
        assert s.messages[-1][0] == 3 and "contact.mu" in s.messages[-1][1], s.messages[-1]
        # setting an output is refused
        s.fmu.reset()
        with pytest.raises(Exception):
            s.fmu.setReal([s.v["object.base.x"].valueReference], [1.0])
        assert "'object.base.x' is not an input" in s.messages[-1][1]
    finally:
        s.fmu.freeInstance()
        shutil.rmtree(s.dir, ignore_errors=True)


def test_a_parameter_set_before_initialisation_is_the_scenario_key(fmu_path, tmp_path):
    """--param contact.mu: the FMU with mu = 0.2 set through fmi2SetReal is
    capdyn run --set contact.mu=0.2, bit for bit (0.35 s)."""
    h5 = str(tmp_path / "mu.h5")
    run_cli("run", "-q", SCEN, "-o", h5, *SETS, "--set", "contact.mu=0.2", "--set", "simulation.duration=0.3505859375")
    r = simulate_fmu(fmu_path, output_interval=DT, stop_time=0.3505859375, start_values={"contact.mu": 0.2})
    with h5py.File(h5, "r") as f:
        np.testing.assert_array_equal(r["object.base.x"], f["systems/object/base_pos"][:, 0])
        np.testing.assert_array_equal(r["object.base.wz"], f["systems/object/base_angvel"][:, 2])


FRESH = r"""
import sys
from fmpy import simulate_fmu
r = simulate_fmu(sys.argv[1], stop_time=0.1, output_interval=2.0 ** -10)
print(len(r), r["object.base.y"][-1])
"""


def test_runs_in_a_fresh_directory_without_capdyn_or_LD_LIBRARY_PATH(fmu_path, tmp_path):
    fresh = tmp_path / "fresh"
    fresh.mkdir()
    shutil.copy(fmu_path, fresh / "c.fmu")
    (fresh / "run.py").write_text(FRESH)
    env = {k: v for k, v in os.environ.items() if not k.startswith("CAPDYN") and k != "LD_LIBRARY_PATH"}
    env["PATH"] = "/usr/bin:/bin"  # no build tree on the path
    p = subprocess.run([sys.executable, "run.py", "c.fmu"], cwd=fresh, env=env, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split()[0] == "104"  # 0.1 s at 2^-10 s: 103 steps and t = 0
    # every non-system library resolves inside the FMU's binaries/linux64/
    d = extract(str(fresh / "c.fmu"))
    try:
        so = os.path.join(d, "binaries", "linux64", "capdyn_fmu.so")
        ldd = subprocess.run(["ldd", so], env=env, capture_output=True, text=True).stdout
        assert "not found" not in ldd
        for lib in ("libccd", "libtomlplusplus", "libqhull_r", "libgslcblas"):
            line = [l for l in ldd.splitlines() if lib in l]
            assert line and os.path.join(d, "binaries", "linux64") in line[0], (lib, ldd)
        assert "libgsl.so" not in ldd and "libhdf5" not in ldd and BUILD not in ldd
        rp = subprocess.run(["readelf", "-d", so], capture_output=True, text=True).stdout
        assert "[$ORIGIN]" in rp
    finally:
        shutil.rmtree(d, ignore_errors=True)


def test_cli_errors(tmp_path, capdyn_bin):
    p = subprocess.run([BIN, "fmu", SCEN], capture_output=True, text=True)
    assert p.returncode == 2 and "missing -o FILE.fmu" in p.stderr
    p = subprocess.run([BIN, "fmu", SCEN, "-o", str(tmp_path / "x.fmu"), "--input", "nope"], capture_output=True, text=True)
    assert p.returncode == 2 and "--input 'nope': no such input" in p.stderr
    p = subprocess.run([BIN, "fmu", SCEN, "-o", str(tmp_path / "x.fmu"), "--param", "contact.mu=abc"], capture_output=True, text=True)
    assert p.returncode == 2 and "not a finite number" in p.stderr
    p = subprocess.run([BIN, "fmu", SCEN, "-o", str(tmp_path / "x.fmu"), "--param", "contact.muu=0.5"], capture_output=True, text=True)
    assert p.returncode == 1 and "contact.muu" in p.stderr
    # a scenario with an include does not travel alone
    p = subprocess.run([BIN, "fmu", scenario("capture_detumble.toml"), "-o", str(tmp_path / "x.fmu")], capture_output=True, text=True)
    assert p.returncode == 1 and "does not load on its own" in p.stderr
    assert not os.path.exists(tmp_path / "x.fmu")
    # --output / --input select the variables
    path = str(tmp_path / "sel.fmu")
    run_cli("fmu", SCEN, "-o", path, "--output", "capture.verdict", "--input", "hand.f0_l0.tau")
    md = read_model_description(path)
    assert sorted(v.name for v in md.modelVariables) == ["capture.verdict", "hand.f0_l0.tau"]
    assert validate_fmu(path) == []
    # the same command writes the same bytes (fixed entry times, no host data)
    again = str(tmp_path / "again.fmu")
    run_cli("fmu", SCEN, "-o", again, "--output", "capture.verdict", "--input", "hand.f0_l0.tau")
    with open(path, "rb") as a, open(again, "rb") as b:
        assert a.read() == b.read()


# A free-flying chaser with a two-joint arm and a soft gripper around a ball
# that drifts sideways off-centre (it pushes the arm). The C controller
# ([control], start = "hold", docs/capture.md) holds the arm by joint
# impedance (w_n 2 rad/s, zeta 1) and closes the gripper from t = 0.
CLOSED_LOOP_C = """\
title = "An arm holds while a soft gripper closes on a ball (FMU closed loop)"

[simulation]
duration = 1.5
gravity = [0.0, 0.0, 0.0]
integrator = "rk8pd"
rtol = 1e-8
atol = 1e-10
h_max = 1e-3
output_dt = 0.01

[contact.rule]
k_soft = 1e3
k_ratio = 10
m_eff = 0.1
zeta = 1.0

[contact]
mu_max = 0.5
mu = 0.4

[[system]]
name = "chaser"
base = "free"
mass = 100.0
inertia = [10.0, 10.0, 10.0]
position = [0.0, 0.0, 0.0]

  [[system.shape]]
  name = "bus"
  type = "box"
  size = [0.4, 0.4, 0.4]

  [[system.link]]
  name = "shoulder"
  axis = [0.0, 0.0, 1.0]
  origin = [0.2, 0.0, 0.0]
  mass = 2.0
  com = [0.15, 0.0, 0.0]
  inertia = [0.002, 0.02, 0.02]

  [[system.link]]
  name = "elbow"
  axis = [0.0, 0.0, 1.0]
  origin = [0.3, 0.0, 0.0]
  mass = 1.5
  com = [0.15, 0.0, 0.0]
  inertia = [0.002, 0.015, 0.015]

[gripper]
type = "soft"
hand = "two_opposed"
system = "chaser"
attach = "elbow"
palm = { size = [0.12, 0.04, 0.06], position = [0.3, 0.0, 0.0], rpy_deg = [0.0, 0.0, -90.0] }
links = [0.08, 0.07]
masses = [0.05, 0.04]
radius = 0.008
spacing = 0.1
torque = 0.3
motor = { stall_torque = 0.5, noload_speed = 5.0 }
close = { on = "trigger" }
finger_joint = { spring = 0.02, damping = 0.005, limit_deg = [-5.0, 120.0] }

[[target]]
name = "target"
mass = 0.3
inertia = [1e-4, 1e-4, 1e-4]
position = [0.88, 0.012, 0.0]
velocity = [0.0, -0.02, 0.0]
shape = { name = "ball", type = "sphere", radius = 0.03 }

[control]
type = "capture"
start = "hold"
fixture = "target/ball"
grasp_point = [0.0, 0.08, 0.0]
impedance = { frequency = 2.0, damping_ratio = 1.0 }

[capture]
object = "target"
"""


def test_python_pd_loop_at_100_Hz_captures_as_the_C_controller(tmp_path):
    """fmpy steps the FMU at 100 Hz; a PD law in Python holds the arm (zero-order
    hold, constant gains of the order of the C impedance: H_jj w_n^2, 2 zeta w_n
    H_jj at the initial pose) and closes the gripper (the soft gripper's motor
    commands, the torque the C controller commands). The same scenario without
    [control] and with the gripper's own closing schedule pushed past the run.
    The verdict equals the C run's, its time within 2 communication steps
    (0.02 s); both hold the arm within 0.01 rad of its initial angles."""
    c = tmp_path / "c.toml"
    c.write_text(CLOSED_LOOP_C)
    h5 = str(tmp_path / "c.h5")
    run_cli("run", "-q", str(c), "-o", h5)
    with h5py.File(h5, "r") as f:
        verdict_c = f.attrs["capture_verdict"]
        verdict_c = verdict_c.decode() if isinstance(verdict_c, bytes) else verdict_c
        t_c = float(f.attrs["capture_t"])
        q_c = f["systems/chaser/q"][:, :2]
    assert verdict_c == "captured"
    assert np.max(np.abs(q_c - q_c[0])) < 0.01
    p = tmp_path / "p.toml"
    text = CLOSED_LOOP_C[: CLOSED_LOOP_C.index("[control]")] + CLOSED_LOOP_C[CLOSED_LOOP_C.index("[capture]"):]
    text = text.replace('close = { on = "trigger" }', "close = { start = 100.0 }")
    p.write_text(text)
    fmu = str(tmp_path / "p.fmu")
    run_cli("fmu", str(p), "-o", fmu)
    md = read_model_description(fmu)
    v = {x.name: x.valueReference for x in md.modelVariables}
    d = extract(fmu)
    s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier, instanceName="pd")
    try:
        s.instantiate()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.exitInitializationMode()
        joints = ["chaser.shoulder", "chaser.elbow"]
        q0 = np.array(s.getReal([v[j + ".q"] for j in joints]))
        kp, kd = np.array([1.6, 0.3]), np.array([1.6, 0.3])  # [N m/rad], [N m s/rad]
        h, dev = 0.01, 0.0
        for k in range(150):  # 1.5 s
            q = np.array(s.getReal([v[j + ".q"] for j in joints]))
            qd = np.array(s.getReal([v[j + ".qd"] for j in joints]))
            dev = max(dev, float(np.max(np.abs(q - q0))))
            s.setReal([v[j + ".tau"] for j in joints], list(kp * (q0 - q) - kd * qd))
            s.setReal([v["chaser/f0_motor.ctrl"], v["chaser/f1_motor.ctrl"]], [0.3, 0.3])
            s.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
        verdict = s.getInteger([v["capture.verdict"]])[0]
        t_v = s.getReal([v["capture.time"]])[0]
        assert verdict == 1  # cd_verdict: captured
        assert abs(t_v - t_c) <= 0.02, (t_v, t_c)
        assert dev < 0.01
        s.terminate()
    finally:
        s.freeInstance()
        shutil.rmtree(d, ignore_errors=True)


def test_a_control_scenario_fmu_is_capdyn_run_and_offers_no_input_its_controller_owns(tmp_path):
    """The [control] controller (start = "hold") runs inside the FMU as in
    capdyn run: bit-identical at every communication point (2^-7 s, 0.5 s).
    The inputs it writes (arm joint torques, the gripper motors it closes) are
    not offered; the fingers' joint torques and the base wrenches are."""
    c = tmp_path / "c.toml"
    c.write_text(CLOSED_LOOP_C)
    sets = ["--set", "simulation.output_dt=0.0078125", "--set", "simulation.duration=0.5"]
    h5 = str(tmp_path / "c.h5")
    run_cli("run", "-q", str(c), "-o", h5, *sets)
    fmu = str(tmp_path / "c.fmu")
    run_cli("fmu", str(c), "-o", fmu, *sets)
    names = {v.name for v in read_model_description(fmu).modelVariables}
    assert "chaser.shoulder.tau" not in names and "chaser.elbow.tau" not in names
    assert "chaser/f0_motor.ctrl" not in names
    assert {"chaser.f0_l0.tau", "chaser.base.torque_z", "target.base.force_y"} <= names
    r = simulate_fmu(fmu)
    with h5py.File(h5, "r") as f:
        np.testing.assert_array_equal(r["time"], f["time"][:])
        for j, n in enumerate(["shoulder", "elbow"]):
            np.testing.assert_array_equal(r[f"chaser.{n}.q"], f["systems/chaser/q"][:, j])
        np.testing.assert_array_equal(r["target.base.y"], f["systems/target/base_pos"][:, 1])
        np.testing.assert_array_equal(r["chaser.base.wz"], f["systems/chaser/base_angvel"][:, 2])
