# SPDX-License-Identifier: Apache-2.0
"""canola._linkbase.LinkBase: the two kinds of link (python-can's, the C link) implement
every method the base leaves to them, and a kind that leaves one out fails when it is
made, not when the first frame or call reaches the missing method."""

from __future__ import annotations

import pytest

from canola._linkbase import LinkBase
from canola._native import NativeLink
from canola._pylink import Link


def test_both_kinds_implement_every_abstract_method() -> None:
    assert LinkBase.__abstractmethods__ >= {"now_us", "in_thread", "enter_app", "leave_app",
                                            "wait", "_start_thread", "_stop_thread"}
    assert Link.__abstractmethods__ == frozenset()
    assert NativeLink.__abstractmethods__ == frozenset()


def test_a_kind_missing_a_method_fails_when_made() -> None:
    class Incomplete(LinkBase):
        def now_us(self) -> int:
            return 0

    with pytest.raises(TypeError, match="abstract"):
        Incomplete(None, None)  # type: ignore[arg-type]
