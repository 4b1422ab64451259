"""`capdyn export RESULTS.h5 gltf` (docs/results-format.md, "glTF export"):
the binary glTF read back with pygltflib carries the results file's poses.

Facts checked, on the user scenario of the plot tests (tests/plots/) and a
shipped capture scenario cut short:
- one node per body of /model/bodies, named by its full_name, children of
  one root node that turns z-up into y-up (-90 deg about x);
- each body node's translation and rotation (x, y, z, w) at rest equal the
  body's pose at the first exported sample, and its animation samplers'
  keyframes equal /systems/*/body_x and body_quat at every exported sample
  (read with h5py), to float32 precision: |error| <= 2 ulp of float32 of the
  value (translation), 1e-7 (unit quaternion components);
- the keyframe times equal /time;
- every body that has a shape or a check point has a mesh whose vertices lie
  on its shapes (a sphere's vertices at its radius from its centre).
"""
import os
import subprocess

import h5py
import numpy as np
import pygltflib
import pytest

from conftest import ROOT, run_cli

USER = os.path.join(ROOT, "tests", "plots", "user_grasp.toml")


def export_glb(tmp_path, scenario, *run_args, export_args=()):
    h5 = str(tmp_path / "run.h5")
    glb = tmp_path / "run.glb"
    run_cli("run", scenario, "-q", "-o", h5, *run_args)
    with open(glb, "wb") as f:
        p = subprocess.run([os.environ.get("CAPDYN_BIN", os.path.join(ROOT, "build", "capdyn")), "export", h5, "gltf",
                            *export_args], stdout=f, stderr=subprocess.PIPE)
    assert p.returncode == 0, p.stderr.decode()
    return h5, pygltflib.GLTF2().load_binary(str(glb))


def accessor(g, i):
    a = g.accessors[i]
    v = g.bufferViews[a.bufferView]
    data = g.binary_blob()
    ncomp = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[a.type]
    assert a.componentType == pygltflib.FLOAT
    off = (v.byteOffset or 0) + (a.byteOffset or 0)
    arr = np.frombuffer(data, dtype="<f4", count=a.count * ncomp, offset=off)
    return arr.reshape(a.count, ncomp) if ncomp > 1 else arr


def poses(h5):
    """(time, body_x (n, nbody, 3), body_quat (n, nbody, 4) w x y z, bodies) from the file"""
    with h5py.File(h5, "r") as f:
        n = int(f.attrs["committed_samples"])
        t = f["time"][:n]
        bodies = f["model/bodies"][:]
        nbody = len(bodies)
        X = np.zeros((n, nbody, 3))
        Q = np.zeros((n, nbody, 4))
        for name, grp in f["systems"].items():
            b0 = int(grp.attrs["body_first"])
            nb = int(grp.attrs["nbody"])
            X[:, b0:b0 + nb] = grp["body_x"][:n]
            Q[:, b0:b0 + nb] = grp["body_quat"][:n]
        names = [b["full_name"].decode() for b in bodies]
    return t, X, Q, names


def check_poses(h5, g, sel=None):
    t, X, Q, names = poses(h5)
    if sel is not None:
        t, X, Q = t[sel], X[sel], Q[sel]
    root = g.nodes[g.scenes[g.scene].nodes[0]]
    np.testing.assert_allclose(root.rotation, [-np.sqrt(0.5), 0, 0, np.sqrt(0.5)], atol=1e-9)
    assert root.children == list(range(1, len(names) + 1))
    node_of = {g.nodes[c].name: c for c in root.children}
    assert sorted(node_of) == sorted(names)
    anim = g.animations[0]
    chans = {(ch.target.node, ch.target.path): anim.samplers[ch.sampler] for ch in anim.channels}
    assert len(chans) == 2 * len(names)
    for b, name in enumerate(names):
        node = g.nodes[node_of[name]]
        q_xyzw = Q[:, b, [1, 2, 3, 0]] / np.linalg.norm(Q[:, b], axis=1)[:, None]
        tol_x = 2 * np.spacing(np.abs(X[:, b]).astype(np.float32)).astype(float) + 1e-30
        np.testing.assert_array_less(np.abs(np.array(node.translation) - X[0, b]), tol_x[0] + 1e-12)
        np.testing.assert_allclose(node.rotation, q_xyzw[0], rtol=0, atol=1e-7)
        st = chans[(node_of[name], "translation")]
        sr = chans[(node_of[name], "rotation")]
        assert st.interpolation == "LINEAR" and sr.interpolation == "LINEAR"
        np.testing.assert_allclose(accessor(g, st.input), t, rtol=1e-7, atol=0)
        kx = accessor(g, st.output)
        kq = accessor(g, sr.output)
        assert kx.shape == X[:, b].shape and kq.shape == q_xyzw.shape
        assert np.all(np.abs(kx - X[:, b]) <= tol_x), f"{name}: translation differs beyond float32"
        np.testing.assert_allclose(kq, q_xyzw, rtol=0, atol=1e-7, err_msg=name)
    return node_of


def test_user_scenario_poses_read_back_equal_the_results_file(tmp_path):
    h5, g = export_glb(tmp_path, USER)
    node_of = check_poses(h5, g)
    # the probe's ball: a sphere of radius 0.028 m at the body origin; its
    # mesh's shape primitive has every vertex at that radius (float32)
    mesh = g.meshes[g.nodes[node_of["probe"]].mesh]
    shape_prim = [p for p in mesh.primitives if g.materials[p.material].name.startswith("system")]
    assert len(shape_prim) == 1
    v = accessor(g, shape_prim[0].attributes.POSITION)
    r = np.linalg.norm(v, axis=1)
    ball = r[v[:, 1] < 0.015]                 # the stem reaches down to y = 0.05 - 0.025 - 0.008 = 0.017
    assert ball.size > 100
    np.testing.assert_allclose(ball, 0.028, rtol=1e-6)
    # every hand link has a mesh (rods, check points)
    with h5py.File(h5, "r") as f:
        for b in f["model/bodies"][:]:
            assert g.nodes[node_of[b["full_name"].decode()]].mesh is not None


def test_frames_option_exports_those_samples(tmp_path):
    h5, g = export_glb(tmp_path, USER, export_args=("--frames", "5"))
    n = len(poses(h5)[0])
    sel = np.round(np.linspace(0, n - 1, 5)).astype(int)
    check_poses(h5, g, sel)


def test_capture_scenario_poses_read_back_equal_the_results_file(tmp_path):
    h5, g = export_glb(tmp_path, os.path.join(ROOT, "scenarios", "capture_handrail_tumbling.toml"),
                       "--set", "simulation.duration=0.1")
    check_poses(h5, g)


def test_refuses_a_terminal_and_unknown_what(tmp_path):
    h5 = str(tmp_path / "run.h5")
    run_cli("run", USER, "-q", "-o", h5, "--set", "simulation.duration=0.01")
    p = subprocess.run([os.environ.get("CAPDYN_BIN", os.path.join(ROOT, "build", "capdyn")), "export", h5, "gltf", "x"],
                       capture_output=True, text=True)
    assert p.returncode != 0 and "'gltf' takes no argument, got 'x'" in p.stderr


def rows(text):
    """frames of a `capdyn export` geometry output: list of lists of split rows"""
    frames = []
    for line in text.splitlines():
        if line.startswith("# frame"):
            frames.append([])
        elif line.strip() and not line.startswith("#") and frames:
            frames[-1].append(line.split())
    return frames


def quat_R(q):
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def test_edges_and_forces_in_the_frame_of_the_target(tmp_path):
    """`capdyn export edges|forces --frame BODY` (the close-up of plots/capture.sh):
    in the probe's own frame its shapes' edges do not move while it is pushed
    about (to 1e-9 m); the forces rows equal the results file's contacts,
    -(fn normal + ft) rotated into the probe's frame at the contact point
    relative to its origin (1e-7 relative: 10 printed digits); `between` is 1
    for the hand's check points on the probe."""
    h5 = str(tmp_path / "run.h5")
    run_cli("run", USER, "-q", "-o", h5)
    edges = rows(run_cli("export", h5, "edges", "--frames", "5", "--frame", "probe"))
    own = [np.array([[float(v) for v in r[:3]] for r in f if r[4] == "0"]) for f in edges]
    assert len(own) == 5 and own[0].shape[0] > 50
    for f in own[1:]:
        np.testing.assert_allclose(f, own[0], rtol=0, atol=1e-9)
    world = rows(run_cli("export", h5, "edges", "--frames", "5"))
    moved = [np.array([[float(v) for v in r[:3]] for r in f if r[4] == "0"]) for f in world]
    assert np.max(np.abs(moved[-1] - moved[0])) > 1e-4   # the probe did move in the world
    forces = rows(run_cli("export", h5, "forces", "--at", "end", "--frame", "probe", "--precision", "17"))[0]
    with h5py.File(h5, "r") as f:
        n = int(f.attrs["committed_samples"])
        fn = f["contacts/fn"][n - 1]
        ft = f["contacts/ft"][n - 1]
        pt = f["contacts/point"][n - 1]
        nr = f["contacts/normal"][n - 1]
        mode = f["contacts/mode"][n - 1]
        X = f["systems/probe/body_x"][n - 1, 0]
        R = quat_R(f["systems/probe/body_quat"][n - 1, 0])
    active = [k for k in range(len(mode)) if mode[k] > 0]
    assert sorted(int(r[9]) for r in forces) == active and len(active) == 6
    for r in forces:
        k = int(r[9])
        F = -(fn[k] * nr[k] + ft[k])
        np.testing.assert_allclose([float(v) for v in r[3:6]], R.T @ F, rtol=1e-7, atol=1e-12)
        np.testing.assert_allclose([float(v) for v in r[0:3]], R.T @ (pt[k] - X), rtol=1e-7, atol=1e-12)
        assert float(r[6]) == pytest.approx(fn[k], rel=1e-12)
        assert r[10] == "1" and r[11].startswith("hand/") and r[12] == "probe"
