# SPDX-License-Identifier: Apache-2.0
"""Hooks the cffi extension into the build and the C core into the sdist; the metadata is in
pyproject.toml, but for the version, read from the C core's include/canola/version.h.

The extension is compiled from the repository's C sources around python/ (see
src/canola/_build_core.py). An sdist is built away from them (and ``python -m build`` builds
the wheel from the sdist), so the sdist carries a copy in csrc/, where the builder looks first.
"""

import importlib.util
import os
import shutil

from setuptools import setup
from setuptools.command.sdist import sdist

_BUILDER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "src", "canola",
                        "_build_core.py")


def _builder():  # type: ignore[no-untyped-def]
    """src/canola/_build_core.py as a module (it knows where the C sources are)."""
    spec = importlib.util.spec_from_file_location("_canola_build_core", _BUILDER)
    assert spec is not None and spec.loader is not None
    builder = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(builder)
    return builder


class SdistWithCore(sdist):  # type: ignore[misc]
    """The sdist, plus the C files the extension is built from, in csrc/."""

    def make_release_tree(self, base_dir: str, files: list[str]) -> None:
        # setuptools lists the extension's sources (../src/*.c) among the files; placed
        # under base_dir they would land beside python/ (python/src/*.c), outside the sdist:
        # they go into csrc/ below instead.
        inside = [f for f in files if not os.path.normpath(f).startswith(os.pardir)]
        super().make_release_tree(base_dir, inside)
        root, names = _builder().c_files()
        for name in names:
            target = os.path.join(base_dir, "csrc", name)
            os.makedirs(os.path.dirname(target), exist_ok=True)
            shutil.copy2(os.path.join(root, name), target)


setup(version=_builder().version(), cffi_modules=["src/canola/_build_core.py:ffibuilder"],
      cmdclass={"sdist": SdistWithCore})
