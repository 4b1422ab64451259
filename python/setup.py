# The cffi extension capdyn._capdyn (API mode), built by capdyn/_build.py.
# Everything else is in pyproject.toml.
from setuptools import setup

setup(cffi_modules=["capdyn/_build.py:ffibuilder"])
