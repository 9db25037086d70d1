# SPDX-License-Identifier: Apache-2.0
"""File and data formats: what CANopen files and values look like, read and written.

- :mod:`~canola.formats.eds`: EDS/DCF (CiA 306), read, checked, written (lines by
  :mod:`~canola.formats._ini`; PDO mapping rules by :mod:`~canola.formats._eds_pdo`)
- :mod:`~canola.formats.edstools`: checks, DCFs, diffs and tables over parsed files
- :mod:`~canola.formats.odgen`: C object dictionaries generated from an EDS/DCF
- :mod:`~canola.formats.concise`: concise DCF (0x1F22, CiA 302)
- :mod:`~canola.formats.datatypes`: the basic data types and CiA 306 number syntax;
  :mod:`~canola.formats.values`: Python values <-> wire bytes and CiA 309-3 text

``canola.eds``, ``canola.values`` and ``canola.odgen`` stay importable under those names.
"""
