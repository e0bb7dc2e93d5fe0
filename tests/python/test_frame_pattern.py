# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""The frame-pattern helpers (sss/util/frame_pattern.h)."""

import pytest

import sss


@pytest.mark.parametrize("path,frame,expanded", [
    ("a.%04d.ptc", 7, "a.0007.ptc"),
    ("a.%d.ptc", 12, "a.12.ptc"),
    ("a.####.ptc", 42, "a.0042.ptc"),
    ("a.$F4.ptc", -3, "a.-003.ptc"),  # printf: the sign counts in the width
    ("a.${F}.ptc", 5, "a.5.ptc"),
    ("plain.ptc", None, "plain.ptc"),
])
def test_expand(path, frame, expanded):
    assert sss.has_frame_pattern(path) == (path != "plain.ptc")
    assert sss.expand_frame_pattern(path, frame) == expanded


def test_errors():
    with pytest.raises(sss.UsageError) as e:
        sss.expand_frame_pattern("x.####.ptc", what="input")
    assert str(e.value) == ("input: 'x.####.ptc' has a frame pattern; "
                            "give the frame with frame=N")
    assert sss.has_frame_pattern("x.#.ptc")
    with pytest.raises(sss.UsageError, match="#"):
        sss.expand_frame_pattern("x.#.ptc", 1)
