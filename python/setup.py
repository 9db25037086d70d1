"""Only there to hook the cffi extension into the build; metadata is in pyproject.toml."""

from setuptools import setup

setup(cffi_modules=["src/canola/_build_core.py:ffibuilder"])
