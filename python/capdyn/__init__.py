"""capdyn: contact dynamics of free-flying space robots, from Python.

    import capdyn
    sc = capdyn.load("scenarios/capture_handrail.toml", set={"simulation.duration": 2.0})
    sim = capdyn.Simulation(sc)
    res = sim.run(until_verdict=True)
    print(res.capture.verdict, res.capture.t, res.capture.peak_fn)

See docs/python.md. The engine is libcapdyn_io.so / libcapdyn.so through
cffi (API mode); capdyn.ffi and capdyn.lib give the raw C API.
"""
from ._capdyn import ffi, lib
from .core import (HAVE_BUILDERS, CapdynError, Capture, Hand, Model, Options, RunResult, Scenario, Simulation,
                   SystemState, load, loads, version)
from .results import Results

__version__ = "0.1.0"
__all__ = ["HAVE_BUILDERS", "Hand", "CapdynError", "Capture", "Model", "Options", "RunResult", "Scenario", "Simulation", "SystemState",
           "Results", "load", "loads", "version", "ffi", "lib"]
