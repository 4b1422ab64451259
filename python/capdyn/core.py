"""capdyn from Python: models, scenarios, simulations (docs/python.md).

Everything goes through the cffi extension capdyn._capdyn (API mode) over
libcapdyn_io.so / libcapdyn.so. Rules kept here:
  * every argument is checked in Python before it reaches C (types, sizes,
    finiteness where C would not check, ids in range), so that no input
    from Python can crash the interpreter; the engine's own errors come back
    as CapdynError carrying its message;
  * the simulation data's memory block is allocated by Python (through the
    data's allocator, cd_data_create_ex), so the numpy views on it keep that
    memory alive: a view never dangles, even after the simulation is closed
    (it then holds the last values).
"""
import math
import os
import tempfile
import time
from collections import namedtuple

import numpy as np

from ._capdyn import ffi, lib

__all__ = ["CapdynError", "Model", "Scenario", "Simulation", "Capture", "RunResult", "Hand", "load", "loads",
           "version", "HAVE_BUILDERS"]


class CapdynError(Exception):
    """An error reported by the engine: .status (cd_status, int), .status_name
    (cd_status_string, e.g. "invalid argument") and .message (the engine's
    one-line message, err.msg)."""

    def __init__(self, status, message, result=None):
        self.status = int(status)
        self.status_name = _str(lib.cd_status_string(self.status))
        self.message = message
        self.result = result  # RunResult of a run() that failed, else None
        super().__init__(f"{message} ({self.status_name})" if message else self.status_name)


def _str(p):
    return ffi.string(p).decode("utf-8", "replace") if p != ffi.NULL else None


def _raise(status, err, what=None):
    msg = ffi.string(err.msg).decode("utf-8", "replace")
    if what and not msg:
        msg = what
    raise CapdynError(status, msg)


def _err():
    e = ffi.new("cd_error *")
    e.status = lib.CD_OK
    return e


def version():
    """cd_version() of the loaded library, e.g. "0.1.0"."""
    return _str(lib.cd_version())


# ---- argument checks ---------------------------------------------------------

def _real(v, name, finite=True):
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name}: expected a number, got {type(v).__name__}")
    v = float(v)
    if finite and not math.isfinite(v):
        raise ValueError(f"{name}: expected a finite number, got {v}")
    return v


def _int(v, name, lo=None, hi=None):
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)):
        raise TypeError(f"{name}: expected an integer, got {type(v).__name__}")
    v = int(v)
    if (lo is not None and v < lo) or (hi is not None and v >= hi):
        rng = f"[{lo}, {hi})" if hi is not None else f">= {lo}"
        raise ValueError(f"{name}: expected an integer in {rng}, got {v}")
    if not -2**31 <= v < 2**31:
        raise ValueError(f"{name}: {v} does not fit a C int")
    return v


def _vec(v, n, name, finite=True):
    """A sequence of n finite numbers -> float64 array (copied)."""
    try:
        a = np.array(v, dtype=np.float64).ravel()
    except (TypeError, ValueError) as e:
        raise TypeError(f"{name}: expected {n} numbers: {e}") from None
    if n is not None and a.size != n:
        raise ValueError(f"{name}: expected {n} numbers, got {a.size}")
    if finite and not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: expected finite numbers, got {a.tolist()}")
    return a


def _cstr(s, name):
    if isinstance(s, os.PathLike):
        s = os.fspath(s)
    if isinstance(s, str):
        b = s.encode("utf-8", "surrogateescape")
    elif isinstance(s, bytes):
        b = s
    else:
        raise TypeError(f"{name}: expected a string, got {type(s).__name__}")
    if b"\0" in b:
        raise ValueError(f"{name}: the string contains a NUL character")
    return ffi.new("char[]", b)


def _fill(desc, fields, keep, what):
    """Sets fields of a cffi struct from a dict: arrays from sequences of the
    exact length, numbers checked, strings kept alive in keep."""
    for k, v in fields.items():
        if v is None:
            continue
        if k.startswith("_") or not hasattr(desc, k):
            raise TypeError(f"{what}: unknown field '{k}'")
        cur = getattr(desc, k)
        t = ffi.typeof(cur) if isinstance(cur, ffi.CData) else None
        if t is not None and t.kind == "array":
            a = _vec(v, t.length, f"{what}.{k}")
            for i in range(t.length):
                cur[i] = a[i]
        elif t is not None and t.kind == "pointer" and t.item.cname == "char":
            p = _cstr(v, f"{what}.{k}")
            keep.append(p)
            setattr(desc, k, p)
        elif isinstance(cur, float):
            setattr(desc, k, _real(v, f"{what}.{k}"))
        elif isinstance(cur, int):
            setattr(desc, k, _int(v, f"{what}.{k}"))
        else:
            raise TypeError(f"{what}: field '{k}' cannot be set from Python here")


def _enum(v, table, name):
    if isinstance(v, str):
        key = v.lower()
        if key not in table:
            raise ValueError(f"{name}: expected one of {sorted(table)}, got '{v}'")
        return table[key]
    return _int(v, name, 0, max(table.values()) + 1)


_BASE = {"free": lib.CD_BASE_FREE, "fixed": lib.CD_BASE_FIXED}
_JOINT = {"revolute": lib.CD_JOINT_REVOLUTE, "prismatic": lib.CD_JOINT_PRISMATIC}
_SHAPE = {"plane": lib.CD_SHAPE_PLANE, "sphere": lib.CD_SHAPE_SPHERE, "box": lib.CD_SHAPE_BOX,
          "cylinder": lib.CD_SHAPE_CYLINDER, "capsule": lib.CD_SHAPE_CAPSULE, "convex": lib.CD_SHAPE_CONVEX}
_ACT = {"none": lib.CD_ACT_NONE, "constant": lib.CD_ACT_CONSTANT, "table": lib.CD_ACT_TABLE,
        "pd": lib.CD_ACT_PD, "steps": lib.CD_ACT_STEPS}
_PRESC = {"none": lib.CD_PRESCRIBE_NONE, "velocity": lib.CD_PRESCRIBE_VELOCITY,
          "waypoints": lib.CD_PRESCRIBE_WAYPOINTS}
_FINGER = {"space": lib.CD_FINGER_SPACE, "torque_switch": lib.CD_FINGER_TORQUE_SWITCH}
_STEPPERS = {_str(lib.cd_stepper_name(i)): i for i in range(lib.CD_STEP_NTYPES)}
_VERDICT = {lib.CD_VERDICT_UNRESOLVED: "unresolved", lib.CD_VERDICT_CAPTURED: "captured",
            lib.CD_VERDICT_ESCAPED: "escaped", lib.CD_VERDICT_CAGED: "caged"}


# ---- options -----------------------------------------------------------------

class Options:
    """The integration options (cd_options) of a model (before its data are
    created) or of a simulation (d->opt, between calls). Attribute access;
    stepper by name ("rk8pd", "rk4", "ros34pw2", ...)."""
    _fields = ("stepper", "rtol", "atol", "h_init", "h_max", "h_min", "h_fixed", "max_steps", "event_tol",
               "dwell", "v_reg", "fd_eps", "max_evals", "equilibrium_start")
    _fixed_after_create = ("stepper", "equilibrium_start", "h_init")

    def __init__(self, owner, ptr, frozen=()):
        object.__setattr__(self, "_owner", owner)
        object.__setattr__(self, "_p", ptr)
        object.__setattr__(self, "_frozen", frozen)

    def __getattr__(self, k):
        if k not in Options._fields:
            raise AttributeError(f"options: no option '{k}' (options: {', '.join(Options._fields)})")
        self._owner._live()
        v = getattr(self._p, k)
        return _str(lib.cd_stepper_name(v)) if k == "stepper" else v

    def __setattr__(self, k, v):
        if k not in Options._fields:
            raise AttributeError(f"options: no option '{k}' (options: {', '.join(Options._fields)})")
        if k in self._frozen:
            raise AttributeError(f"options.{k} is fixed when the simulation is created: set it on the model")
        self._owner._live()
        if k == "stepper":
            v = _enum(v, _STEPPERS, "options.stepper")
        elif k in ("max_steps", "max_evals", "equilibrium_start"):
            v = _int(v, f"options.{k}", 0)
        else:
            v = _real(v, f"options.{k}")
        trial = ffi.new("cd_options *", self._p[0])
        setattr(trial, k, v)
        err = _err()
        st = lib.cd_options_check(trial, err)
        if st != lib.CD_OK:
            _raise(st, err)
        setattr(self._p, k, v)

    def as_dict(self):
        return {k: getattr(self, k) for k in Options._fields}

    def __repr__(self):
        return f"Options({self.as_dict()})"


# ---- models ------------------------------------------------------------------

class _ModelView:
    """What Model and Scenario share: sizes and name lookups of a cd_model."""

    def _live(self):
        if self._mp is None:
            raise ValueError("the model has been freed")
        return self._mp

    def _check_final(self):
        if not self._live().finalized:
            raise ValueError("the model is not finalized (call finalize())")

    nsys = property(lambda s: s._live().nsys, doc="systems")
    nbody = property(lambda s: s._live().nbody, doc="bodies (bases and links)")
    nslot = property(lambda s: s._live().nslot, doc="contact slots")
    nu = property(lambda s: s._live().nu, doc="actuators (entries of ctrl)")
    nv = property(lambda s: s._live().nv, doc="generalized velocities")
    ny = property(lambda s: s._live().ny, doc="continuous state size")
    finalized = property(lambda s: bool(s._live().finalized))

    @property
    def gravity(self):
        return np.array(list(self._live().gravity))

    def system_names(self):
        m = self._live()
        return [_str(m.sys_name[i]) for i in range(m.nsys)]

    def body_names(self):
        m = self._live()
        return [_str(m.body_name[i]) for i in range(m.nbody)]

    def slot_bodies(self):
        """(nslot, 2) int array: each contact slot's check-point body and shape body."""
        m = self._live()
        return np.array([[m.cp_body[m.slot_cp[k]], m.shape_body[m.slot_shape[k]]] for k in range(m.nslot)],
                        dtype=np.int64).reshape(m.nslot, 2)

    def body_systems(self):
        """(nbody) int array: the system of each body."""
        m = self._live()
        return np.array([m.body_sys[i] for i in range(m.nbody)], dtype=np.int64)

    def base_body(self, s):
        """Body id of system s's base (bodies of a system are contiguous, the base first)."""
        return self._live().sys_body_adr[self._sys(s)]

    def body_id(self, name):
        """Body id from "system/body" or a unique body name; KeyError if none."""
        i = lib.cd_model_body_id(self._live(), _cstr(name, "body name"))
        if i < 0:
            raise KeyError(f"no body '{name}'")
        return i

    def system_id(self, name):
        i = lib.cd_model_system_id(self._live(), _cstr(name, "system name"))
        if i < 0:
            raise KeyError(f"no system '{name}'")
        return i

    def actuator_id(self, name):
        i = lib.cd_model_actuator_id(self._live(), _cstr(name, "actuator name"))
        if i < 0:
            raise KeyError(f"no actuator '{name}'")
        return i

    def _sys(self, s, name="sys"):
        if isinstance(s, str):
            return self.system_id(s)
        return _int(s, name, 0, self._live().nsys)

    def _body(self, b, name="body"):
        if isinstance(b, str):
            return self.body_id(b)
        return _int(b, name, 0, self._live().nbody)


class Model(_ModelView):
    """A model built in code (cd_model_create, cd_model_add_*). Ids returned
    by the add_* calls are the engine's (body ids, shape ids, ...). After
    finalize() the model is read-only; Simulation(model) runs it.

    Each add_* takes the fields of its C description (model.h) as keyword
    arguments, vectors as sequences of the exact length; anything not given
    keeps the C default (cd_*_desc_default)."""

    def __init__(self, gravity=None):
        p = lib.cd_model_create()
        if p == ffi.NULL:
            raise MemoryError("cd_model_create: out of memory")
        self._mp = p
        self._opt = Options(self, ffi.addressof(p, "opt"))
        if gravity is not None:
            self.gravity = gravity

    def __del__(self):
        # simulations keep their Model object alive, so this runs after them
        p = getattr(self, "_mp", None)
        if p is not None:
            self._mp = None
            lib.cd_model_free(p)

    @property
    def options(self):
        """The model's integration options: the defaults of every simulation
        made from it (stepper is fixed at the simulation's creation)."""
        return self._opt

    def _set_gravity(self, g):
        a = _vec(g, 3, "gravity")
        m = self._live()
        if m.finalized:
            raise ValueError("gravity: the model is finalized")
        for i in range(3):
            m.gravity[i] = a[i]

    gravity = property(_ModelView.gravity.fget, _set_gravity, doc="[m/s^2], world")

    def _call(self, fn, *args):
        """A builder call returning an id (-1 on error)."""
        err = _err()
        r = fn(self._live(), *args, err)
        if r < 0:
            _raise(err.status if err.status != lib.CD_OK else lib.CD_EINVAL, err)
        return r

    def _call_st(self, fn, *args):
        """A builder call returning a cd_status."""
        err = _err()
        st = fn(self._live(), *args, err)
        if st != lib.CD_OK:
            _raise(st, err)

    def add_system(self, name=None, type="free", **fields):
        """A system (a tree with a free or fixed base); returns its id. Fields:
        mass, inertia (9), pos (3), quat (4, w x y z), vel (3), angvel (3)."""
        d = ffi.new("cd_system_desc *", lib.cd_system_desc_default())
        keep = []
        d.type = _enum(type, _BASE, "add_system type")
        _fill(d, dict(fields, name=name), keep, "add_system")
        return self._call(lib.cd_model_add_system, d)

    def add_link(self, sys, parent, type="revolute", name=None, **fields):
        """A link of system sys, jointed to body parent (a body of that
        system); returns its body id. Fields: pos (3), rot (9), axis (3),
        mass, com (3), inertia (9), q0, qd0."""
        sys = self._sys(sys)
        d = ffi.new("cd_link_desc *", lib.cd_link_desc_default())
        keep = []
        d.parent = self._body(parent, "add_link parent")
        d.type = _enum(type, _JOINT, "add_link type")
        _fill(d, dict(fields, name=name), keep, "add_link")
        return self._call(lib.cd_model_add_link, sys, d)

    def add_checkpoint(self, body, pos, radius=0.0):
        """A contact check point (sphere of radius [m] at pos, body frame)."""
        return self._call(lib.cd_model_add_checkpoint, self._body(body), ffi.new("double[3]", list(_vec(pos, 3, "pos"))),
                          _real(radius, "radius"))

    def add_shape(self, body, type, pos=(0, 0, 0), rot=None, size=None, verts=None):
        """A contact shape on body; size per type (model.h); verts (n x 3) for
        "convex". Returns its shape id."""
        t = _enum(type, _SHAPE, "add_shape type")
        rot = np.eye(3).ravel() if rot is None else _vec(rot, 9, "rot")
        sz = ffi.new("double[3]", list(_vec(size, 3, "size"))) if size is not None else ffi.NULL
        if verts is not None:
            v = _vec(verts, None, "verts")
            if v.size == 0 or v.size % 3:
                raise ValueError(f"verts: expected n x 3 numbers, got {v.size}")
            vp, nv = ffi.new("double[]", list(v)), v.size // 3
        else:
            vp, nv = ffi.NULL, 0
        return self._call(lib.cd_model_add_shape, self._body(body), t,
                          ffi.new("double[3]", list(_vec(pos, 3, "pos"))), ffi.new("double[9]", list(rot)),
                          sz, vp, nv)

    def add_law(self, **fields):
        """A contact law (cd_contact_law fields: K, D, p, q, Kt, Dt, mu_s, mu_k,
        pt, qt, pull, damping: 0 linear, 1 Hunt-Crossley, docs/contact.md);
        unspecified fields from cd_contact_law_default()."""
        d = ffi.new("cd_contact_law *", lib.cd_contact_law_default())
        _fill(d, fields, [], "add_law")
        return self._call(lib.cd_model_add_law, d)

    def add_pair(self, sys, shape, law, body=-1):
        """Check points of system sys (only those of body if given) against
        shape, with law."""
        m = self._live()
        b = -1 if body is None or (isinstance(body, int) and body == -1) else self._body(body)
        return self._call(lib.cd_model_add_pair, self._sys(sys), b,
                          _int(shape, "shape", 0, m.nshape), _int(law, "law", 0, m.nlaw))

    def add_actuator(self, joints, ratios=None, type="none", name=None, table=None, **fields):
        """An actuator driving the joint bodies `joints` with transmission
        ratios (default 1 each); returns its index into ctrl. type: "none"
        (torque = ctrl), "constant", "table", "pd", "steps"; table: (times,
        values) for "table"/"steps". Fields: tau0, kp, kd, qref,
        stall_torque, noload_speed."""
        d = ffi.new("cd_actuator_desc *", lib.cd_actuator_desc_default())
        keep = []
        d.type = _enum(type, _ACT, "add_actuator type")
        if isinstance(joints, (int, str, np.integer)):
            joints = [joints]
        jb = [self._body(j, "add_actuator joints") for j in joints]
        if not jb:
            raise ValueError("add_actuator: at least one joint")
        r = _vec(np.ones(len(jb)) if ratios is None else ratios, len(jb), "add_actuator ratios")
        tb = ffi.new("int[]", jb)
        rt = ffi.new("double[]", list(r))
        keep += [tb, rt]
        d.ntrn, d.trn_body, d.trn_ratio = len(jb), tb, rt
        if table is not None:
            t, v = table
            t = _vec(t, None, "table times")
            v = _vec(v, t.size, "table values")
            pt, pv = ffi.new("double[]", list(t)), ffi.new("double[]", list(v))
            keep += [pt, pv]
            d.tbl_t, d.tbl_v, d.ntbl = pt, pv, t.size
        _fill(d, dict(fields, name=name), keep, "add_actuator")
        return self._call(lib.cd_model_add_actuator, d)

    def set_joint(self, body, waypoints=None, prescribe=None, **fields):
        """Passive elements, limits and prescribed motion of a joint body
        (cd_joint_props: stiffness, rest, damping, friction, friction_k,
        friction_d, limited, lower, upper, stop_K, stop_D, stop_p, stop_q,
        presc_v, presc_t0); prescribe: "none", "velocity", "waypoints";
        waypoints: (times, positions)."""
        d = ffi.new("cd_joint_props *", lib.cd_joint_props_default())
        keep = []
        if prescribe is not None:
            d.prescribe = _enum(prescribe, _PRESC, "set_joint prescribe")
        if waypoints is not None:
            t, q = waypoints
            t = _vec(t, None, "waypoint times")
            q = _vec(q, t.size, "waypoint positions")
            pt, pq = ffi.new("double[]", list(t)), ffi.new("double[]", list(q))
            keep += [pt, pq]
            d.presc_t, d.presc_q, d.npresc = pt, pq, t.size
        _fill(d, fields, keep, "set_joint")
        self._call_st(lib.cd_model_set_joint, self._body(body), d)

    def prescribe_base(self, sys, v, w):
        """Constant base velocity v and angular velocity w (world) from t = 0."""
        self._call_st(lib.cd_model_prescribe_base, self._sys(sys), ffi.new("double[3]", list(_vec(v, 3, "v"))),
                   ffi.new("double[3]", list(_vec(w, 3, "w"))))

    def add_finger(self, joints, schedule, type="space", sync=None, ratio=None, name=None, **fields):
        """A clutched finger over the joint bodies `joints` (base to tip),
        closing schedule (times, angles); fields: wire_K, wire_D, threshold,
        grasp_torque, torque_limit, open_at."""
        d = ffi.new("cd_finger_desc *", lib.cd_finger_desc_default())
        keep = []
        d.type = _enum(type, _FINGER, "add_finger type")
        jb = [self._body(j, "add_finger joints") for j in joints]
        if not jb:
            raise ValueError("add_finger: at least one joint")
        pj = ffi.new("int[]", jb)
        keep.append(pj)
        d.njoint, d.joint_body = len(jb), pj
        for k, v in (("sync", sync), ("ratio", ratio)):
            if v is not None:
                p = ffi.new("double[]", list(_vec(v, len(jb), f"add_finger {k}")))
                keep.append(p)
                setattr(d, k, p)
        t, q = schedule
        t = _vec(t, None, "schedule times")
        q = _vec(q, t.size, "schedule angles")
        pt, pq = ffi.new("double[]", list(t)), ffi.new("double[]", list(q))
        keep += [pt, pq]
        d.sched_t, d.sched_q, d.nsched = pt, pq, t.size
        _fill(d, dict(fields, name=name), keep, "add_finger")
        return self._call(lib.cd_model_add_finger, d)

    # -- the builders (include/capdyn/build.h; capdyn.HAVE_BUILDERS) -----------
    def _need_builders(self):
        if not HAVE_BUILDERS:
            raise NotImplementedError("this capdyn has no builders (include/capdyn/build.h): hands, targets and "
                                      "chasers come from scenarios ([gripper], [[target]])")

    def _shape_descs(self, shapes, keep, what):
        """A list of dicts (cd_shape_desc fields; type a shape name or
        "handrail"; verts n x 3) -> a cd_shape_desc[] kept alive in keep."""
        if shapes is None:
            return ffi.NULL, 0
        if isinstance(shapes, dict):
            shapes = [shapes]
        n = len(shapes)
        arr = ffi.new("cd_shape_desc[]", max(n, 1))
        keep.append(arr)
        for i, sh in enumerate(shapes):
            if not isinstance(sh, dict):
                raise TypeError(f"{what}[{i}]: expected a dict of cd_shape_desc fields")
            arr[i] = lib.cd_shape_desc_default()
            f = dict(sh)
            if "type" in f:
                arr[i].type = _enum(f.pop("type"), dict(_SHAPE, handrail=lib.CD_SHAPE_NTYPES), f"{what}[{i}].type")
            if f.get("verts") is not None:
                v = _vec(f.pop("verts"), None, f"{what}[{i}].verts")
                if v.size == 0 or v.size % 3:
                    raise ValueError(f"{what}[{i}].verts: expected n x 3 numbers, got {v.size}")
                pv = ffi.new("double[]", list(v))
                keep.append(pv)
                arr[i].verts, arr[i].nvert = pv, v.size // 3
            _fill(arr[i], f, keep, f"{what}[{i}]")
        return arr, n

    def build_shape(self, body, type, **fields):
        """cd_build_shape: a shape, or a handrail (type "handrail": a capsule
        bar and two box posts) on body; fields of cd_shape_desc (radius,
        length, size -- full edges --, height, post, pos, rot, verts).
        Returns the id of the first shape added."""
        self._need_builders()
        keep = []
        arr, _ = self._shape_descs([dict(fields, type=type)], keep, "build_shape")
        return self._call(lib.cd_build_shape, self._body(body), arr)

    def add_target(self, name=None, shapes=None, **fields):
        """cd_build_target: a rigid target (a free base unless fixed=1) with
        its shapes (a list of dicts as build_shape's); fields of
        cd_target_desc (mass, inertia, pos, quat, vel, angvel, fixed,
        prescribed). Returns its system id."""
        self._need_builders()
        keep = []
        d = ffi.new("cd_target_desc *", lib.cd_target_desc_default())
        d.shapes, d.nshape = self._shape_descs(shapes, keep, "add_target shapes")
        _fill(d, dict(fields, name=name), keep, "add_target")
        return self._call(lib.cd_build_target, d)

    def add_chaser(self, name=None, shapes=None, arm=None, arm_joint=None, **fields):
        """cd_build_chaser: a base with its shapes, an arm (a list of dicts of
        cd_link_desc fields; "parent" an index into the arm, -1 the base;
        "type" revolute or prismatic) with optional joint properties
        (arm_joint: a list of dicts of cd_joint_props fields or None), and
        reaction wheels (wheels=1, wheel_kp, wheel_kd, wheel_torque).
        Arm link i is body base_body(sys) + 1 + i. Returns its system id."""
        self._need_builders()
        keep = []
        d = ffi.new("cd_chaser_desc *", lib.cd_chaser_desc_default())
        d.shapes, d.nshape = self._shape_descs(shapes, keep, "add_chaser shapes")
        arm = list(arm or [])
        if arm:
            links = ffi.new("cd_link_desc[]", len(arm))
            keep.append(links)
            for i, l in enumerate(arm):
                if not isinstance(l, dict):
                    raise TypeError(f"add_chaser arm[{i}]: expected a dict of cd_link_desc fields")
                links[i] = lib.cd_link_desc_default()
                f = dict(l)
                links[i].parent = _int(f.pop("parent", i - 1), f"add_chaser arm[{i}].parent", -1, i)
                if "type" in f:
                    links[i].type = _enum(f.pop("type"), _JOINT, f"add_chaser arm[{i}].type")
                _fill(links[i], f, keep, f"add_chaser arm[{i}]")
            d.arm, d.narm = links, len(arm)
            if arm_joint is not None:
                if len(arm_joint) != len(arm):
                    raise ValueError(f"add_chaser arm_joint: expected {len(arm)} entries, got {len(arm_joint)}")
                jp = ffi.new("cd_joint_props[]", len(arm))
                keep.append(jp)
                for i, j in enumerate(arm_joint):
                    jp[i] = lib.cd_joint_props_default()
                    if j is not None:
                        _fill(jp[i], j, keep, f"add_chaser arm_joint[{i}]")
                d.arm_joint = jp
        elif arm_joint is not None:
            raise ValueError("add_chaser: arm_joint without an arm")
        _fill(d, dict(fields, name=name), keep, "add_chaser")
        return self._call(lib.cd_build_chaser, d)

    def add_hand(self, type="space", layout="two_opposed", name=None, **fields):
        """cd_build_hand (stage 1): the palm and the fingers; type "soft",
        "tako", "space", "torque_switch"; layout "two_opposed", "three_120",
        "two_pairs", "two_interleaved"; fields of cd_hand_desc (attach_body,
        palm_size, palm_pos, nlink, link_length, link_mass, radius, spacing,
        joint_limited, joint_lower, joint_upper, joint_stop_K, joint_stop_D, q0, torque, close_time,
        close_angle, close_start, clutch_threshold, ...: arrays of
        CD_HAND_MAX_LINKS entries may be given shorter, the rest 0). Returns a
        Hand; then add_hand_drive(hand, ...) once the targets exist."""
        self._need_builders()
        keep = []
        d = ffi.new("cd_hand_desc *", lib.cd_hand_desc_default())
        d.type = _enum(type, {"soft": lib.CD_HAND_SOFT, "tako": lib.CD_HAND_TAKO, "space": lib.CD_HAND_SPACE,
                              "torque_switch": lib.CD_HAND_TORQUE_SWITCH}, "add_hand type")
        d.layout = _enum(layout, {"two_opposed": lib.CD_HAND_TWO_OPPOSED, "three_120": lib.CD_HAND_THREE_120,
                                  "two_pairs": lib.CD_HAND_TWO_PAIRS,
                                  "two_interleaved": lib.CD_HAND_TWO_INTERLEAVED}, "add_hand layout")
        f = dict(fields, name=name)
        if f.get("attach_body") is not None and f["attach_body"] != -1:
            f["attach_body"] = self._body(f["attach_body"], "attach_body")
        for k in ("link_length", "link_mass", "joint_lower", "joint_upper", "joint_stop_K", "joint_stop_D", "q0",
                  "ratio"):
            if f.get(k) is not None:  # per-link arrays: the given links, the rest as the default
                cur = getattr(d, k)
                v = _vec(f.pop(k), None, f"add_hand.{k}")
                if v.size > len(cur):
                    raise ValueError(f"add_hand.{k}: at most {len(cur)} links, got {v.size}")
                for i in range(v.size):
                    cur[i] = v[i]
        _fill(d, f, keep, "add_hand")
        out = ffi.new("cd_hand *")
        self._call(lib.cd_build_hand, d, out)
        return Hand(d, out, keep)

    def add_hand_drive(self, hand, law=None, targets=()):
        """cd_build_hand_drive (stage 2): the hand's motors or clutched
        fingers and its contact pairs with law (a dict of cd_contact_law
        fields, default cd_contact_law_default(); or ("rule", k_soft,
        k_ratio, m_eff, zeta, mu) for cd_contact_law_from_rule) against
        every shape of the target systems."""
        self._need_builders()
        if not isinstance(hand, Hand):
            raise TypeError(f"add_hand_drive: expected the Hand of add_hand, got {type(hand).__name__}")
        if isinstance(law, tuple) and law and law[0] == "rule":
            if len(law) != 6:
                raise ValueError("add_hand_drive law: ('rule', k_soft, k_ratio, m_eff, zeta, mu)")
            c = ffi.new("cd_contact_law *", lib.cd_contact_law_from_rule(
                *(_real(x, "add_hand_drive law") for x in law[1:])))
        else:
            c = ffi.new("cd_contact_law *", lib.cd_contact_law_default())
            if law is not None:
                if not isinstance(law, dict):
                    raise TypeError("add_hand_drive law: a dict of cd_contact_law fields or ('rule', ...)")
                _fill(c, law, [], "add_hand_drive law")
        ts = [self._sys(t, "add_hand_drive targets") for t in ([targets] if isinstance(targets, (int, str)) else targets)]
        tp = ffi.new("int[]", ts or [0])
        self._call_st(lib.cd_build_hand_drive, hand._desc, hand._c, c, tp, len(ts))
        return hand

    def finalize(self):
        """Validates and freezes the model (cd_model_finalize)."""
        self._call_st(lib.cd_model_finalize)
        return self


HAVE_BUILDERS = hasattr(lib, "cd_build_hand")


class Hand:
    """What add_hand / add_hand_drive made (cd_hand): sys, palm, palm_shape,
    nfinger, nlink, finger_body[f][j] (link bodies, base to tip), ncp; after
    the drive: act (motor indices into ctrl), act_close_u, clutch (clutched
    finger ids), law."""

    def __init__(self, desc, c, keep):
        self._desc, self._c, self._keep = desc, c, keep

    def __getattr__(self, k):
        c = self.__dict__["_c"]
        if k == "finger_body":
            return [[c.finger_body[f][j] for j in range(c.nlink)] for f in range(c.nfinger)]
        if k == "act":
            return [c.act[i] for i in range(c.nact)]
        if k == "act_close_u":
            return [c.act_close_u[i] for i in range(c.nact)]
        if k == "clutch":
            return [c.clutch[i] for i in range(c.nclutch)]
        if k in ("sys", "palm", "palm_shape", "nfinger", "nlink", "ncp", "nact", "nclutch", "law"):
            return getattr(c, k)
        raise AttributeError(k)

    def __repr__(self):
        return (f"Hand(sys={self.sys}, palm={self.palm}, fingers={self.finger_body}, ncp={self.ncp}, "
                f"act={self.act}, clutch={self.clutch})")


# ---- scenarios ---------------------------------------------------------------

def _toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        if not math.isfinite(v):
            return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
        return repr(float(v))
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
    if isinstance(v, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"override value: cannot write a {type(v).__name__} as TOML")


def _overrides(set):
    """--set overrides: a list of "key=value" strings, or a dict {key: value}
    (values written as TOML)."""
    if set is None:
        return []
    if isinstance(set, dict):
        out = []
        for k, v in set.items():
            if not isinstance(k, str):
                raise TypeError("override keys must be strings")
            out.append(f"{k}={_toml_value(v)}")
        return out
    if isinstance(set, (str, bytes)):
        set = [set]
    out = []
    for s in set:
        if not isinstance(s, str):
            raise TypeError(f"override: expected a 'key=value' string, got {type(s).__name__}")
        if "=" not in s or s.startswith("="):
            raise ValueError(f"override: expected KEY=VALUE, got '{s}'")
        out.append(s)
    return out


class Scenario(_ModelView):
    """A loaded scenario (cd_scenario_load): its finalized model and run
    settings. Use load() / loads()."""

    def __init__(self, path, set=None, _display=None):
        ov = _overrides(set)
        cpath = _cstr(path, "scenario path")
        keep = [_cstr(s, "override") for s in ov]
        arr = ffi.new("const char *[]", keep + [ffi.NULL])
        err = _err()
        p = lib.cd_scenario_load(cpath, arr, len(keep), err)
        if p == ffi.NULL:
            msg = ffi.string(err.msg).decode("utf-8", "replace")
            if _display:
                msg = msg.replace(os.fspath(path), _display)
            raise CapdynError(err.status if err.status != lib.CD_OK else lib.CD_EINVAL, msg)
        self._sp = p
        self._mp = p.model
        self.path = _display or os.fspath(path)
        self.overrides = ov

    def __del__(self):
        p = getattr(self, "_sp", None)
        if p is not None:
            self._sp = self._mp = None
            lib.cd_scenario_free(p)

    def _s(self):
        if self._sp is None:
            raise ValueError("the scenario has been freed")
        return self._sp

    title = property(lambda s: _str(s._s().title))
    text = property(lambda s: _str(s._s().text), doc="the scenario text as read")
    duration = property(lambda s: s._s().duration, doc="[s]")
    output_dt = property(lambda s: s._s().output_dt, doc="[s]")
    interpolate = property(lambda s: bool(s._s().interpolate), doc="samples by dense output")
    has_capture = property(lambda s: s._s().capture_hand >= 0 and s._s().capture_object >= 0)
    has_control = property(lambda s: s._s().control != ffi.NULL)
    capture_hand = property(lambda s: s._s().capture_hand, doc="system of the [gripper]'s hand, -1 if none")
    capture_object = property(lambda s: s._s().capture_object, doc="the system it is to capture, -1 if none")
    max_rhs_evals = property(lambda s: s._s().max_rhs_evals)
    max_wall_time = property(lambda s: s._s().max_wall_time)

    @property
    def options(self):
        """The model's integration options, as loaded (read them; a
        simulation's own copy is Simulation.options)."""
        return Options(self, ffi.addressof(self._live(), "opt"), frozen=Options._fields)

    def simulation(self, **kw):
        return Simulation(self, **kw)


def load(path, set=None):
    """Loads a scenario file with --set overrides (a list of "key=value"
    strings in TOML value syntax, or a dict {key: value})."""
    return Scenario(path, set)


def loads(text, set=None, name="<string>"):
    """Loads a scenario from a TOML string (written to a private temporary
    file, removed at once; relative include paths therefore do not resolve:
    give absolute ones). Error messages name the file as `name`."""
    if not isinstance(text, str):
        raise TypeError(f"loads: expected a TOML string, got {type(text).__name__}")
    if "\0" in text:
        raise ValueError("loads: the text contains a NUL character")
    with tempfile.TemporaryDirectory(prefix="capdyn-") as d:
        p = os.path.join(d, "scenario.toml")
        with open(p, "w", encoding="utf-8") as f:
            f.write(text)
        return Scenario(p, set, _display=name)


# ---- the simulation ----------------------------------------------------------

class _Arena:
    """Memory of one cd_data: blocks allocated as Python objects (cffi
    arrays); views keep their block alive."""

    def __init__(self):
        self.blocks = {}

    def find(self, addr):
        for base, (buf, size) in self.blocks.items():
            if base <= addr < base + size:
                return buf, base
        raise RuntimeError("capdyn: a data pointer outside the data's memory")


@ffi.def_extern(onerror=lambda *a: None)
def _cd_py_alloc(size, ctx):
    arena = ffi.from_handle(ctx)
    buf = ffi.new("double[]", max(1, (size + 7) // 8))  # 8-byte aligned, zeroed
    p = ffi.cast("void *", buf)
    arena.blocks[int(ffi.cast("uintptr_t", p))] = (buf, size)
    return p


@ffi.def_extern(onerror=lambda *a: None)
def _cd_py_free(ptr, ctx):
    if ptr != ffi.NULL:
        ffi.from_handle(ctx).blocks.pop(int(ffi.cast("uintptr_t", ptr)), None)


@ffi.def_extern(onerror=lambda e, v, tb: _cb_error(v))
def _cd_py_step(m, d, user):
    return ffi.from_handle(user)._on_step()


@ffi.def_extern(onerror=lambda e, v, tb: _cb_error(v))
def _cd_py_sample(m, s, user):
    return ffi.from_handle(user)._on_sample(s)


_pending = []


def _cb_error(v):
    # an exception inside a callback (including KeyboardInterrupt): kept,
    # the C call is asked to stop (return 1) and the exception re-raised
    _pending.append(v)
    return 1


SystemState = namedtuple("SystemState", "pos quat q vel angvel qd")
SystemState.__doc__ = """Views into the state y of one system: base CoM position (3), quaternion
(4, w x y z), joint positions, base CoM velocity (3), angular velocity (3,
world), joint rates; base parts None for a fixed base."""


class Capture:
    """The capture verdict and figures of merit of a run (verdict.h; the
    root attributes capture_* of a results file, docs/results-format.md)."""
    _fields = ("verdict", "t", "t_capture", "t_escape", "t_cage", "peak_fn", "peak_tau", "epsilon", "n_stick", "n_slip",
               "offset", "enclosed", "v_rel", "w_rel", "dP", "dL", "base_angle_max", "base_rate_end", "t_trigger",
               "t_rigidise", "v_rel_end", "w_rel_end", "tau_arm_max")

    def __init__(self, **kw):
        for k in Capture._fields:
            setattr(self, k, kw.get(k))

    @property
    def captured(self):
        return self.verdict == "captured"

    def as_dict(self):
        return {k: getattr(self, k) for k in Capture._fields if getattr(self, k) is not None}

    def __repr__(self):
        return "Capture(" + ", ".join(f"{k}={v!r}" for k, v in self.as_dict().items()) + ")"


RunResult = namedtuple("RunResult", "status message t nsamples capture fn_step_max nrhs nsteps nevents")
RunResult.__doc__ = """How a run() ended: status "ok" (or the engine's status name), the message
as capdyn run writes it, the time reached, samples taken, the Capture (or
None), the largest normal force over every accepted step, statistics."""


class Simulation:
    """A simulation: one cd_data of a finalized Model or a Scenario (with the
    scenario's built-in controller, [control], and its capture monitor).

    Views (numpy arrays on the engine's memory, never copies): y, ydot,
    ctrl, qfrc_applied, xfrc_applied, xfrc_body, q(s), qd(s), system(s),
    slot_fn, slot_ft, slot_x, slot_point, slot_normal, slot_mode, body_x,
    body_c, body_R, udot, tau, qfrc_actuator, qfrc_passive, act_force.
    Their values are those of the engine at every moment: read them between
    calls; a step, run, state set or reset changes them in place. Inputs
    (ctrl, qfrc_applied, xfrc_*, y) are writable, outputs read-only. The
    memory never moves and stays alive as long as a view exists."""

    def __init__(self, source, event_capacity=None, monitor=None):
        self._dp = None
        self._ctl = None
        if isinstance(source, Scenario):
            self._src = source
            sc = source._s()
            cap = sc.event_capacity if event_capacity is None else event_capacity
        elif isinstance(source, Model):
            source._check_final()
            self._src = source
            sc = None
            cap = 0 if event_capacity is None else event_capacity
        else:
            raise TypeError(f"Simulation: expected a Model or a Scenario, got {type(source).__name__}")
        cap = _int(cap, "event_capacity", 0, 1 << 24)
        self._m = source._live()
        self._sc = sc
        self._arena = _Arena()
        self._arena_h = ffi.new_handle(self._arena)
        self._self_h = ffi.new_handle(self)
        alloc = ffi.new("cd_allocator *")
        alloc.alloc = lib._cd_py_alloc
        alloc.free = lib._cd_py_free
        alloc.ctx = self._arena_h
        err = _err()
        d = lib.cd_data_create_ex(self._m, cap, alloc, err)
        if d == ffi.NULL:
            _raise(err.status if err.status != lib.CD_OK else lib.CD_ENOMEM, err)
        self._dp = d
        if sc is not None and sc.control != ffi.NULL:
            c = lib.cd_ctrl_create(self._m, sc.control, err)
            if c == ffi.NULL:
                self.close()
                _raise(err.status, err)
            self._ctl = c
            lib.cd_ctrl_install(c, d)
        self._opt = Options(self, ffi.addressof(d, "opt"), frozen=Options._fixed_after_create)
        self._views = {}
        self._mon = None
        self._merit = ffi.new("cd_ctrl_merit *")
        self._merit_on = False
        if monitor is not None:
            self.set_monitor(**monitor)
        elif sc is not None and sc.capture_hand >= 0 and sc.capture_object >= 0:
            self._init_monitor(lib.cd_scenario_monitor_opts(sc))

    # -- lifetime
    def close(self):
        """Frees the engine's data now (views keep their memory and last
        values); any later call raises ValueError."""
        d, c = self._dp, self._ctl
        self._dp = self._ctl = None
        if c is not None:
            lib.cd_ctrl_free(c)
        if d is not None:
            lib.cd_data_free(d)

    def __del__(self):
        if getattr(self, "_dp", None) is not None:
            self.close()

    def __enter__(self):
        return self

    def __exit__(self, *a):
        self.close()

    def _live(self):
        if self._dp is None:
            raise ValueError("the simulation is closed")
        return self._dp

    # -- sizes, time, options
    model = property(lambda s: s._src, doc="the Model or Scenario it runs")
    options = property(lambda s: s._opt, doc="this simulation's integration options (d->opt)")

    @property
    def t(self):
        return self._live().t

    @t.setter
    def t(self, v):
        self._live().t = _real(v, "t")

    @property
    def stats(self):
        s = self._live().stats
        return {k: getattr(s, k) for k in ("nrhs", "nsteps", "nrejected", "nevents", "nlocate_steps", "nwarn_geom",
                                           "nwarn_dwell", "nwarn_budget", "nrenorm", "nrestart", "njac", "h_last",
                                           "h_min_seen", "h_max_seen")}

    # -- views
    def _view(self, field, n, shape=None, dtype=np.float64, writable=False):
        key = (field, shape)
        v = self._views.get(key)
        if v is not None:
            return v
        d = self._live()
        p = getattr(d, field)
        if n == 0 or p == ffi.NULL:
            v = np.zeros(shape or (0,), dtype=dtype)
        else:
            addr = int(ffi.cast("uintptr_t", p))
            buf, base = self._arena.find(addr)
            v = np.frombuffer(ffi.buffer(buf), dtype=dtype, count=n, offset=addr - base)
            if shape is not None:
                v = v.reshape(shape)
        v.flags.writeable = writable
        self._views[key] = v
        return v

    def _ptr_view(self, p, n, writable):
        if p == ffi.NULL:
            return None
        addr = int(ffi.cast("uintptr_t", p))
        buf, base = self._arena.find(addr)
        v = np.frombuffer(ffi.buffer(buf), dtype=np.float64, count=n, offset=addr - base)
        v.flags.writeable = writable
        return v

    y = property(lambda s: s._view("y", s._m.ny, writable=True), doc="continuous state (ny), writable")
    ydot = property(lambda s: s._view("ydot", s._m.ny))
    ctrl = property(lambda s: s._view("ctrl", s._m.nu, writable=True), doc="actuator commands (nu), an input")
    qfrc_applied = property(lambda s: s._view("qfrc_applied", s._m.nv, writable=True))
    xfrc_applied = property(lambda s: s._view("xfrc_applied", 6 * s._m.nbody, (s._m.nbody, 6), writable=True))
    xfrc_body = property(lambda s: s._view("xfrc_body", 6 * s._m.nbody, (s._m.nbody, 6), writable=True))
    udot = property(lambda s: s._view("udot", s._m.nv))
    tau = property(lambda s: s._view("tau", s._m.nv))
    qfrc_actuator = property(lambda s: s._view("qfrc_actuator", s._m.nv))
    qfrc_passive = property(lambda s: s._view("qfrc_passive", s._m.nv))
    act_force = property(lambda s: s._view("act_force", s._m.nu))
    body_x = property(lambda s: s._view("body_x", 3 * s._m.nbody, (s._m.nbody, 3)))
    body_c = property(lambda s: s._view("body_c", 3 * s._m.nbody, (s._m.nbody, 3)))
    body_R = property(lambda s: s._view("body_R", 9 * s._m.nbody, (s._m.nbody, 3, 3)))
    body_v = property(lambda s: s._view("body_v", 3 * s._m.nbody, (s._m.nbody, 3)), doc="CoM velocities [m/s]")
    body_w = property(lambda s: s._view("body_w", 3 * s._m.nbody, (s._m.nbody, 3)), doc="angular velocities")
    finger_mode = property(lambda s: s._view("finger_mode", s._m.nfinger, dtype=np.dtype(f"i{ffi.sizeof('int')}")),
                           doc="clutched fingers: 0 engaged, 1 released (the clutch disengaged)")
    slot_fn = property(lambda s: s._view("slot_fn", s._m.nslot), doc="normal force per slot [N]")
    slot_ft = property(lambda s: s._view("slot_ft", 3 * s._m.nslot, (s._m.nslot, 3)))
    slot_x = property(lambda s: s._view("slot_x", s._m.nslot))
    slot_point = property(lambda s: s._view("slot_point", 3 * s._m.nslot, (s._m.nslot, 3)))
    slot_normal = property(lambda s: s._view("slot_normal", 3 * s._m.nslot, (s._m.nslot, 3)))
    slot_mode = property(lambda s: s._view("slot_mode", s._m.nslot, dtype=np.dtype(f"i{ffi.sizeof('int')}")),
                         doc="0 open, 1 stick, 2 slip")

    def system(self, s=0):
        """SystemState of system s: views into y (writable)."""
        key = ("system", s)
        v = self._views.get(key)
        if v is None:
            si = self._src._sys(s)
            st = lib.cd_state_of(self._m, self._live(), si)
            nj = st.njoint
            v = SystemState(*(self._ptr_view(getattr(st, k), n, True)
                              for k, n in (("pos", 3), ("quat", 4), ("q", nj), ("vel", 3), ("angvel", 3), ("qd", nj))))
            self._views[key] = v
        return v

    def q(self, s=0):
        """Joint positions of system s (view into y)."""
        return self.system(s).q

    def qd(self, s=0):
        """Joint rates of system s (view into y)."""
        return self.system(s).qd

    # -- stepping
    def _status(self, st, err):
        if _pending:
            e = _pending.pop()
            _pending.clear()
            raise e
        if st != lib.CD_OK:
            _raise(st, err)

    def step(self, h):
        """One step of a fixed-rate loop: advances by exactly h (cd_step)."""
        h = _real(h, "h")
        err = _err()
        self._status(lib.cd_step(self._m, self._live(), h, err), err)

    def advance(self, t_end):
        """Advances to t_end exactly, locating every event (cd_sim_advance)."""
        t_end = _real(t_end, "t_end")
        err = _err()
        self._status(lib.cd_sim_advance(self._m, self._live(), t_end, ffi.NULL, ffi.NULL, err), err)

    def forward(self):
        """Evaluates the current state (cd_forward): outputs valid."""
        err = _err()
        st = lib.cd_forward(self._m, self._live())
        if st != lib.CD_OK:
            raise CapdynError(st, f"cd_forward: {_str(lib.cd_status_string(st))} at t = {self.t:.9g} s")

    def kinematics(self):
        lib.cd_kinematics(self._m, self._live())

    def reset(self):
        """Back to the model's initial state (cd_data_reset), the controller
        and monitor too."""
        err = _err()
        self._status(lib.cd_data_reset(self._m, self._live(), err), err)
        if self._ctl is not None:
            # a new controller (fresh memory) installed before the old one is freed:
            # the data never points at a freed controller
            c = lib.cd_ctrl_create(self._m, self._sc.control, err)
            if c == ffi.NULL:
                _raise(err.status, err)
            lib.cd_ctrl_install(c, self._dp)
            old, self._ctl = self._ctl, c
            lib.cd_ctrl_free(old)
        if self._mon is not None:
            self._init_monitor(self._mon.opt)

    def mass_matrix(self, s=0):
        """Mass matrix of system s (new array, sys_ndof^2), after kinematics."""
        si = self._src._sys(s)
        n = self._m.sys_ndof[si]
        H = np.zeros((n, n))
        d = self._live()
        lib.cd_kinematics(self._m, d)
        lib.cd_mass_matrix(self._m, d, si, ffi.cast("double *", ffi.from_buffer(H)))
        return H

    def momentum(self, s=0):
        """(kinetic energy, P, L about the CoM, L about the origin, CoM) of system s."""
        si = self._src._sys(s)
        d = self._live()
        lib.cd_kinematics(self._m, d)
        ke = ffi.new("double *")
        out = [np.zeros(3) for _ in range(4)]
        lib.cd_momentum(self._m, d, si, ke, *(ffi.cast("double *", ffi.from_buffer(a)) for a in out))
        return (ke[0], *out)

    # -- state
    def state_size(self):
        n = lib.cd_state_size(self._m)
        if self._ctl is not None:
            n += lib.cd_ctrl_state_size(self._ctl)
        return n

    def state_get(self):
        """The complete state (cd_state_get, then the built-in controller's
        memory, cd_ctrl_state_get) as a new float64 array."""
        d = self._live()
        buf = np.empty(self.state_size())
        p = ffi.cast("double *", ffi.from_buffer(buf))
        lib.cd_state_get(self._m, d, p)
        if self._ctl is not None:
            lib.cd_ctrl_state_get(self._ctl, p + lib.cd_state_size(self._m))
        return buf

    def state_set(self, state):
        """Restores a state from state_get() of a simulation of the same model:
        continuing is bit-identical to not having stopped."""
        d = self._live()
        a = np.ascontiguousarray(state, dtype=np.float64)
        if a.ndim != 1 or a.size != self.state_size():
            raise ValueError(f"state_set: expected a state of {self.state_size()} numbers (state_get), "
                             f"got shape {a.shape}")
        p = ffi.cast("double *", ffi.from_buffer(a))
        err = _err()
        if self._ctl is not None:  # check the controller's part first: nothing changes on error
            trial = lib.cd_ctrl_state_size(self._ctl)
            saved = np.empty(trial)
            lib.cd_ctrl_state_get(self._ctl, ffi.cast("double *", ffi.from_buffer(saved)))
            st = lib.cd_ctrl_state_set(self._ctl, p + lib.cd_state_size(self._m), err)
            if st != lib.CD_OK:
                _raise(st, err)
        st = lib.cd_state_set(self._m, d, p, err)
        if st != lib.CD_OK:
            if self._ctl is not None:
                lib.cd_ctrl_state_set(self._ctl, ffi.cast("double *", ffi.from_buffer(saved)), ffi.NULL)
            _raise(st, err)
        if self._ctl is not None:
            # again after cd_state_set, whose evaluation ran the controller
            # (as tests/test_capture.c restores: data, then controller)
            lib.cd_ctrl_state_set(self._ctl, p + lib.cd_state_size(self._m), ffi.NULL)

    def state_copy(self, other):
        """Takes the complete state of another simulation of the same model
        (cd_state_copy)."""
        if not isinstance(other, Simulation):
            raise TypeError(f"state_copy: expected a Simulation, got {type(other).__name__}")
        if other._m != self._m:
            raise ValueError("state_copy: the other simulation runs another model")
        if (self._ctl is None) != (other._ctl is None):
            raise ValueError("state_copy: one simulation has a controller, the other not")
        err = _err()
        st = lib.cd_state_copy(self._m, self._live(), other._live(), err)
        if st != lib.CD_OK:
            _raise(st, err)
        if self._ctl is not None:
            buf = np.empty(lib.cd_ctrl_state_size(other._ctl))
            p = ffi.cast("double *", ffi.from_buffer(buf))
            lib.cd_ctrl_state_get(other._ctl, p)
            st = lib.cd_ctrl_state_set(self._ctl, p, err)
            if st != lib.CD_OK:
                _raise(st, err)

    # -- capture monitor
    def set_monitor(self, hand, object, **opts):
        """Watches the run for a capture verdict (verdict.h): hand and object
        systems; opts: v_max, w_max, dwell, workspace, feature, palm,
        palm_pos, palm_rot."""
        o = ffi.new("cd_monitor_opts *", lib.cd_monitor_opts_default())
        o.hand = self._src._sys(hand, "hand")
        o.object = self._src._sys(object, "object")
        if "palm" in opts and opts["palm"] is not None and opts["palm"] != -1:
            opts["palm"] = self._src._body(opts["palm"], "palm")
        _fill(o, opts, [], "monitor")
        self._init_monitor(o[0])

    def _init_monitor(self, opts):
        mon = ffi.new("cd_monitor *")
        o = ffi.new("cd_monitor_opts *", opts)
        err = _err()
        st = lib.cd_monitor_init(mon, self._m, self._live(), o, err)
        if st != lib.CD_OK:
            _raise(st, err)
        lib.cd_monitor_update(mon, self._m, self._dp)
        self._mon = mon

    def capture(self):
        """The Capture of the monitor so far (None without a monitor)."""
        mon = self._mon
        if mon is None:
            return None
        d = self._live()
        v = _VERDICT.get(mon.verdict, "unresolved")
        eps = ffi.new("double *")
        fc = ffi.new("int *")
        if lib.cd_monitor_quality(mon, self._m, d, eps, fc, _err()) != lib.CD_OK:
            eps[0] = math.nan
        kw = dict(verdict=v, t_capture=mon.t_capture, t_escape=mon.t_escape, t_cage=mon.t_cage,
                  t=mon.t_capture if v == "captured" else mon.t_escape if v == "escaped"
                  else mon.t_cage if v == "caged" else math.nan,
                  peak_fn=mon.peak_fn, peak_tau=mon.peak_tau, epsilon=eps[0], n_stick=mon.n_stick,
                  n_slip=mon.n_slip, offset=np.array(list(mon.offset)), enclosed=bool(mon.enclosed),
                  v_rel=mon.v_rel, w_rel=mon.w_rel)
        if self._ctl is not None and self._merit_on:
            f = self._merit
            kw.update(dP=np.array(list(f.dP)), dL=np.array(list(f.dL)), base_angle_max=f.base_angle_max,
                      base_rate_end=f.base_rate, t_trigger=lib.cd_ctrl_t_trigger(self._ctl),
                      v_rel_end=f.v_rel, w_rel_end=f.w_rel, tau_arm_max=f.tau_arm_max)
            kw["t_rigidise"] = mon.t_capture - kw["t_trigger"] if v == "captured" else math.nan
        return Capture(**kw)

    # -- the run loop of capdyn run (src/cli/run.c, cli_run_loop)
    def _on_step(self):
        d = self._dp
        r = self._run
        if r["max_rhs"] > 0 and d.stats.nrhs > r["max_rhs"]:
            r["budget"] = (f"work budget spent: {d.stats.nrhs} right-hand-side evaluations, more than "
                           f"simulation.max_rhs_evals = {r['max_rhs']:g}, at t = {d.t:.9g} s")
            return 1
        if r["max_wall"] > 0 and time.monotonic() - r["wall0"] > r["max_wall"]:
            r["budget"] = (f"work budget spent: {time.monotonic() - r['wall0']:.1f} s of wall-clock time, more "
                           f"than simulation.max_wall_time = {r['max_wall']:g} s, at t = {d.t:.9g} s")
            return 1
        if self._m.nslot:
            fn = self.slot_fn
            np.maximum(r["fn_max"], fn, out=r["fn_max"])
        smp = r.get("sampler")
        if smp is not None:
            k = lib.cd_sampler_update(smp, self._m, d, lib._cd_py_sample, self._self_h)
            if k < 0:
                r["sample_fail"] = f"an interpolated sample after t = {d.t:.9g} s cannot be evaluated"
                return 1
            return k
        return 0

    def _on_sample(self, s):
        r = self._run
        if s.t >= r["t_end"] * (1.0 - 1e-12):
            return 0  # the final one is taken at the end
        return self._take_sample(s)

    def _take_sample(self, s):
        r = self._run
        r["nsamples"] += 1
        if self._mon is not None:
            lib.cd_monitor_update(self._mon, self._m, s)
        if self._ctl is not None:
            lib.cd_ctrl_merit_update(self._merit, self._ctl, self._m, s)
        if r["on_sample"] is not None:
            if s == self._dp:
                stop = r["on_sample"](self)
            else:
                stop = r["on_sample"](_SampleView(self, s))
            if stop:
                r["user_stop"] = True
                return 1
        # a final verdict only: a cage may still become a grip or let go (verdict.h)
        if self._mon is not None and r["until_verdict"] and self._mon.verdict in (lib.CD_VERDICT_CAPTURED,
                                                                                  lib.CD_VERDICT_ESCAPED):
            r["verdict_stop"] = True
            return 1
        return 0

    def run(self, until=None, until_verdict=False, dt=None, interpolate=None, on_sample=None):
        """Runs as `capdyn run` does (src/cli/run.c): samples at k dt, the
        last exactly at `until` (a run continued from t > 0 takes the
        sample times after t); the capture monitor and the controller's
        figures of merit look at every sample; with until_verdict the run
        ends at the monitor's verdict. Defaults from the scenario
        (duration, output_dt, sampling); a Model's simulation needs until
        and dt. on_sample(view) is called at every sample (view: this
        simulation, or for interpolated samples an object with the same
        read-only views); a true return value stops the run.
        Returns a RunResult; an engine failure raises CapdynError (with
        .result), the state then being the last good one."""
        d = self._live()
        sc = self._sc
        if until is None:
            if sc is None:
                raise ValueError("run: a Model's simulation needs until=")
            until = sc.duration
        if dt is None:
            if sc is None:
                raise ValueError("run: a Model's simulation needs dt=")
            dt = sc.output_dt
        until, dt = _real(until, "until"), _real(dt, "dt")
        if not (until > 0 and dt > 0):
            raise ValueError("run: until and dt must be positive")
        if not until > d.t:
            raise ValueError(f"run: until = {until:g} s is not after the current time {d.t:g} s")
        if not (until / dt <= 1e9):
            raise ValueError(f"run: until / dt = {until / dt:g} samples is more than 1e9")
        if interpolate is None:
            interpolate = bool(sc.interpolate) if sc is not None else False
        if on_sample is not None and not callable(on_sample):
            raise TypeError("run: on_sample must be callable")
        if until_verdict and self._mon is None:
            raise ValueError("run: until_verdict needs a capture monitor (a scenario with a gripper and an "
                             "object, or set_monitor())")
        r = self._run = dict(max_rhs=sc.max_rhs_evals if sc is not None else 0.0,
                             max_wall=sc.max_wall_time if sc is not None else 0.0, wall0=time.monotonic(),
                             fn_max=np.zeros(self._m.nslot), budget=None, sample_fail=None, t_end=until,
                             until_verdict=bool(until_verdict), on_sample=on_sample, nsamples=0,
                             verdict_stop=False, user_stop=False)
        err = _err()
        self._on_step()  # the state at t = 0 counts for the maxima too
        if self._ctl is not None:
            lib.cd_ctrl_merit_init(self._merit, self._ctl, self._m, d)
            self._merit_on = True
        st = lib.CD_OK
        exc = None
        try:
            if interpolate:
                smp = lib.cd_sampler_create(self._m, err)
                if smp == ffi.NULL:
                    _raise(err.status, err)
                smp = ffi.gc(smp, lib.cd_sampler_free)
                r["sampler"] = smp
                st = lib.cd_sampler_begin(smp, self._m, d, 0.0, dt, err)
                if st == lib.CD_OK:
                    st = lib.cd_sim_advance(self._m, d, until, lib._cd_py_step, self._self_h, err)
                if (r["verdict_stop"] or r["user_stop"]) and st == lib.CD_EINTERRUPT:
                    st = lib.CD_OK
                elif st == lib.CD_OK:
                    self._take_sample(d)
            else:
                nout = math.ceil(until / dt - 1e-9)
                for i in range(1, nout + 1):
                    tn = until if i == nout else float(i) * dt
                    if tn > until:
                        tn = until
                    if tn <= d.t:  # a run continued: the sample times still ahead
                        continue
                    st = lib.cd_sim_advance(self._m, d, tn, lib._cd_py_step, self._self_h, err)
                    if st != lib.CD_OK:
                        break
                    if self._take_sample(d):
                        break
        finally:
            if _pending:
                exc = _pending.pop()
                _pending.clear()
            r.pop("sampler", None)
        if exc is not None:
            raise exc
        msg = ffi.string(err.msg).decode("utf-8", "replace")
        if st == lib.CD_EINTERRUPT and r["budget"]:
            msg = r["budget"]
        if r["sample_fail"]:
            st, msg = lib.CD_ENUMERIC, r["sample_fail"]
        if st != lib.CD_OK and not msg:
            msg = f"{_str(lib.cd_status_string(st))} at t = {d.t:.9g} s"
        if st == lib.CD_OK:
            msg = f"finished at t = {d.t:.9g} s"
        res = RunResult(status="ok" if st == lib.CD_OK else _str(lib.cd_status_string(st)), message=msg, t=d.t,
                        nsamples=r["nsamples"], capture=self.capture(),
                        fn_step_max=float(r["fn_max"].max()) if self._m.nslot else 0.0,
                        nrhs=d.stats.nrhs, nsteps=d.stats.nsteps, nevents=d.ev_count)
        if st != lib.CD_OK:
            raise CapdynError(st, msg, result=res)
        return res

    def events(self):
        """The events still in the log, oldest first, as a list of dicts."""
        d = self._live()
        n = min(d.ev_count, d.ev_cap)
        out = []
        for i in range(n):
            e = lib.cd_data_event(d, i)
            out.append(dict(t=e.t, kind=e.kind, kind_name=_str(lib.cd_event_kind_name(e.kind)), slot=e.slot,
                            mode_from=e.mode_from, mode_to=e.mode_to, x=e.x, fn=e.fn, ft=e.ft, body_a=e.body_a,
                            body_b=e.body_b, owner_kind=_str(lib.cd_owner_kind_name(e.owner_kind)),
                            owner=e.owner))
        return out


class _SampleView:
    """An interpolated sample (the sampler's own data) during on_sample:
    t and copies of the main outputs."""

    def __init__(self, sim, s):
        m = sim._m
        self.t = s.t
        self.y = np.frombuffer(ffi.buffer(s.y, 8 * m.ny), dtype=np.float64).copy()
        self.slot_fn = np.frombuffer(ffi.buffer(s.slot_fn, 8 * m.nslot), dtype=np.float64).copy() \
            if m.nslot else np.zeros(0)
        self.slot_mode = np.frombuffer(ffi.buffer(s.slot_mode, ffi.sizeof("int") * m.nslot),
                                       dtype=np.dtype(f"i{ffi.sizeof('int')}")).copy() if m.nslot else np.zeros(0, int)
        self.ctrl = np.frombuffer(ffi.buffer(s.ctrl, 8 * m.nu), dtype=np.float64).copy() if m.nu else np.zeros(0)
