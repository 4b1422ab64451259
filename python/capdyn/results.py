"""Results files (docs/results-format.md) read into numpy through h5py,
with the column names of `capdyn export` (docs/cli.md).

Only committed rows are read (the root attribute committed_samples /
committed_events: the committed-sample rule), so a file still being
written, or left by a killed run, reads like `capdyn export` reads it.
Each table is a dict {column name: 1-D numpy array}, in export's order.
"""
import h5py
import numpy as np

__all__ = ["Results"]


def _s(v):
    return v.decode("utf-8", "replace") if isinstance(v, bytes) else str(v)


def _token(name):
    # as export's token(): a name without blanks, "-" for an empty one
    name = _s(name)
    return "".join("_" if c.isspace() else c for c in name) if name else "-"


class Results:
    """An open results file: Results(path), or `with Results(path) as r:`."""

    def __init__(self, path):
        self.path = path
        self.file = h5py.File(path, "r")
        a = self.file.attrs
        self.n = int(a["committed_samples"])
        self.nevents = int(a.get("committed_events", 0))

    def close(self):
        self.file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @property
    def attrs(self):
        """The root attributes as a dict (strings decoded)."""
        return {k: (_s(v) if isinstance(v, (bytes, str)) else v) for k, v in self.file.attrs.items()}

    def _series(self, path):
        return np.asarray(self.file[path][: self.n])

    def time(self):
        """{"t"}"""
        return {"t": self._series("/time")}

    def systems(self):
        """The system names, in id order."""
        g = self.file["/systems"]
        names = sorted(g.keys(), key=lambda k: int(g[k].attrs["index"]))
        return [_s(g[k].attrs["name"]) for k in names]

    def _group(self, name):
        g = self.file["/systems"]
        for k in g.keys():
            if _s(g[k].attrs["name"]) == name or k == name:
                return g[k]
        raise KeyError(f"no system '{name}' in {self.path} (systems: {', '.join(self.systems())})")

    def system(self, name):
        """export system NAME: t x y z qw qx qy qz vx vy vz wx wy wz, q.JOINT..., qd.JOINT..."""
        g = self._group(name)
        out = {"t": self._series("/time")}
        for ds, cols in (("base_pos", "x y z"), ("base_quat", "qw qx qy qz"), ("base_vel", "vx vy vz"),
                         ("base_angvel", "wx wy wz")):
            a = np.asarray(g[ds][: self.n])
            for i, c in enumerate(cols.split()):
                out[c] = a[:, i]
        nj = int(g.attrs["njoint"])
        if nj > 0:
            names = [_token(x) for x in g.attrs["joint_names"]]
            q, qd = np.asarray(g["q"][: self.n]), np.asarray(g["qd"][: self.n])
            for i, jn in enumerate(names):
                out["q." + jn] = q[:, i]
            for i, jn in enumerate(names):
                out["qd." + jn] = qd[:, i]
        return out

    def contacts(self, active=False):
        """export contacts [--active]: t nopen nstick nslip fn_sum, then per
        slot K: fn.K ft.K (|f_t|) mode.K."""
        t = self._series("/time")
        ns = int(self.file.attrs["nslot"])
        out = {"t": t}
        if ns == 0:
            z = np.zeros(t.size)
            out.update(nopen=z, nstick=z.copy(), nslip=z.copy(), fn_sum=z.copy())
            return out
        fn = self._series("/contacts/fn")
        ft = np.linalg.norm(self._series("/contacts/ft"), axis=2)
        mode = self._series("/contacts/mode").astype(np.int64)
        out["nopen"] = np.sum(mode == 0, axis=1)
        out["nstick"] = np.sum(mode == 1, axis=1)
        out["nslip"] = np.sum(mode == 2, axis=1)
        out["fn_sum"] = fn.sum(axis=1)
        for k in range(ns):
            if active and not (np.any(fn[:, k] != 0) or np.any(mode[:, k] != 0)):
                continue
            out[f"fn.{k}"] = fn[:, k]
            out[f"ft.{k}"] = ft[:, k]
            out[f"mode.{k}"] = mode[:, k]
        return out

    _STEP_PEAKS = ("fn_step_max", "fn_step_body", "fn_step_onset", "ft_step_max", "t_fn_step_body",
                   "t_fn_step_onset")

    def step_peaks(self):
        """The peaks over every integrator step of each slot [N], as capdyn run
        and capdyn info print them (docs/cli.md, "Peak forces";
        /contacts/fn_step_max, fn_step_body -- "peak fn over steps" --,
        fn_step_onset -- "onset transient" --, ft_step_max [N]; t_fn_step_body,
        t_fn_step_onset: when those were reached [s], NaN for never): a dict
        of (nslot) arrays, or None when the file does not store them (written
        before they were, or its run did not close it: NaN forces)."""
        c = self.file.get("/contacts")
        if c is None or any(k not in c for k in self._STEP_PEAKS):
            return None
        out = {k: np.asarray(c[k][()], dtype=np.float64) for k in self._STEP_PEAKS}
        if any(not np.all(np.isfinite(out[k])) for k in self._STEP_PEAKS[:4]):
            return None
        return out

    def slot(self, k):
        """export slot N: t fn ftx fty ftz ft x xdot px py pz nx ny nz vtx vty vtz vt mode."""
        ns = int(self.file.attrs["nslot"])
        if not isinstance(k, (int, np.integer)) or not 0 <= k < ns:
            raise IndexError(f"slot {k}: the model has {ns} slots")
        sl = (slice(0, self.n), k)
        c = self.file["/contacts"]
        ft = np.asarray(c["ft"][sl])
        pt = np.asarray(c["point"][sl])
        nm = np.asarray(c["normal"][sl])
        vt = np.asarray(c["slip_velocity"][sl])
        return {"t": self._series("/time"), "fn": np.asarray(c["fn"][sl]), "ftx": ft[:, 0], "fty": ft[:, 1],
                "ftz": ft[:, 2], "ft": np.linalg.norm(ft, axis=1), "x": np.asarray(c["penetration"][sl]),
                "xdot": np.asarray(c["penetration_rate"][sl]), "px": pt[:, 0], "py": pt[:, 1], "pz": pt[:, 2],
                "nx": nm[:, 0], "ny": nm[:, 1], "nz": nm[:, 2], "vtx": vt[:, 0], "vty": vt[:, 1],
                "vtz": vt[:, 2], "vt": np.linalg.norm(vt, axis=1),
                "mode": np.asarray(c["mode"][sl]).astype(np.int64)}

    def events(self):
        """export events: t kind kind_name slot mode_from mode_to x fn ft body_a
        body_b owner_kind owner (kind_name, body_a, body_b -- full body names --
        and owner_kind as strings; the ids are in self.file["/events"])."""
        if "/events" not in self.file or self.nevents == 0:
            return {k: np.zeros(0) for k in "t kind kind_name slot mode_from mode_to x fn ft body_a body_b "
                    "owner_kind owner".split()}
        from ._capdyn import ffi, lib
        e = np.asarray(self.file["/events"][: self.nevents])
        names = e.dtype.names
        out = {}
        for k in ("t", "kind"):
            out[k] = np.asarray(e[k])
        out["kind_name"] = np.array([ffi.string(lib.cd_event_kind_name(int(x))).decode() for x in e["kind"]])
        for k in ("slot", "mode_from", "mode_to", "x", "fn", "ft"):
            out[k] = np.asarray(e[k])
        full = [_token(b["full_name"]) for b in self.file["/model/bodies"][:]]
        for k in ("body_a", "body_b"):  # as export: the body's full name (system/body), "-" for none
            out[k] = np.array([full[int(i)] if 0 <= int(i) < len(full) else "-" for i in e[k]])
        ok = e["owner_kind"] if "owner_kind" in names else np.zeros(e.size, int)
        out["owner_kind"] = np.array([ffi.string(lib.cd_owner_kind_name(int(x))).decode() for x in ok])
        out["owner"] = np.asarray(e["owner"]) if "owner" in names else np.zeros(e.size, int)
        return out

    @property
    def capture(self):
        """The capture_* root attributes without the prefix (verdict, t,
        peak_fn, ...), or None if the run had no capture verdict."""
        a = self.file.attrs
        if "capture_verdict" not in a:
            return None
        return {k[len("capture_"):]: (_s(v) if isinstance(v, (bytes, str)) else v)
                for k, v in a.items() if k.startswith("capture_")}
