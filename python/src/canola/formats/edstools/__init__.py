# SPDX-License-Identifier: Apache-2.0
"""Tools over parsed EDS/DCF files (:mod:`canola.formats.eds`), the library behind ``canola eds``:

- :mod:`~canola.formats.edstools.check`: the parser's diagnostics as a linter's findings;
- :mod:`~canola.formats.edstools.table`: the dictionary as rows of a table, filtered;
- :mod:`~canola.formats.edstools.dcf`: a DCF from an EDS, a node-ID and checked values;
- :mod:`~canola.formats.edstools.diff`: what differs between two dictionaries, or between a
  dictionary and a device's values.
"""
