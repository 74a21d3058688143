"""Malformed BVH files raise ``BVHError`` naming the line and the problem; fuzzed files either load or
raise ``BVHError``, never another exception and never a hang."""

from __future__ import annotations

import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from motionlab.data.bvh import BVHError, load_bvh, parse_bvh
from motionlab.data.motion import Motion

VALID = """HIERARCHY
ROOT Hips
{
\tOFFSET 0 0 0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT Chest
\t{
\t\tOFFSET 0 5 0
\t\tCHANNELS 3 Zrotation Xrotation Yrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 4 0
\t\t}
\t}
}
MOTION
Frames: 3
Frame Time: 0.0333333
0 1 2 3 4 5 6 7 8
0.5 1 2 30 40 50 60 70 -80
1 1 2 -3e1 4.5E+1 5 6 7 8
"""
LINES = VALID.splitlines()


def with_line(number: int, text: str | None) -> str:
    """VALID with 1-based line ``number`` replaced by ``text`` (deleted when ``None``)."""
    lines = list(LINES)
    if text is None:
        del lines[number - 1]
    else:
        lines[number - 1] = text
    return "\n".join(lines) + "\n"


def test_the_base_file_is_valid() -> None:
    motion = parse_bvh(VALID.encode())
    assert motion.num_frames == 3 and motion.joint_names == ("Hips", "Chest") and motion.fps == 30.0


CASES = [
    # (name, file text or bytes, message fragment, line)
    ("empty file", "", "empty", 1),
    ("blank file", "\n \t\r\n\n", "empty", 1),
    ("binary garbage", bytes(range(256)) * 4, "binary", 1),
    ("binary without NUL", b"\x89PNG\r\n\x1a\n\xff\xfe\xfd" * 20, "expected 'HIERARCHY'", 1),
    ("truncated motion", "\n".join(LINES[:-1]) + "\n", "truncated motion", 17),
    ("truncated hierarchy", "\n".join(LINES[:9]) + "\n", "unexpected end of file", 9),
    ("huge Frames count", with_line(17, "Frames: 999999999999"), "truncated motion", 17),
    ("absurd Frames count", with_line(17, "Frames: " + "9" * 5000), "implausibly large", 17),
    ("more frames than declared", with_line(17, "Frames: 2"), "more frame lines", 21),
    ("zero frames", with_line(17, "Frames: 0"), "positive integer", 17),
    ("fractional frames", with_line(17, "Frames: 3.0"), "positive integer", 17),
    ("too few values", with_line(20, "0 1 2 3 4 5 6 7"), "frame 2 has 8 values", 20),
    ("too many values", with_line(21, "0 1 2 3 4 5 6 7 8 9"), "frame 3 has 10 values", 21),
    ("non-numeric value", with_line(19, "0 1 abc 3 4 5 6 7 8"), "value 3 is not a number", 19),
    ("NaN value", with_line(19, "0 1 nan 3 4 5 6 7 8"), "not a number", 19),
    ("infinite value", with_line(19, "0 1 inf 3 4 5 6 7 8"), "not a number", 19),
    ("overflowing value", with_line(19, "0 1 1e999 3 4 5 6 7 8"), "out of range", 19),
    ("underscore digits", with_line(19, "0 1 1_0 3 4 5 6 7 8"), "not a number", 19),
    (
        "unknown channel",
        with_line(9, "CHANNELS 3 Zrotation Wrotation Yrotation"),
        "unknown channel 'Wrotation'",
        9,
    ),
    ("repeated channel", with_line(9, "CHANNELS 3 Zrotation Zrotation Yrotation"), "listed twice", 9),
    (
        "channel count too small",
        with_line(5, "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation"),
        "declares 6 channels but names only 5",
        5,
    ),
    (
        "channel count not a number",
        with_line(9, "CHANNELS three Zrotation Xrotation Yrotation"),
        "CHANNELS count",
        9,
    ),
    (
        "channel count too large",
        with_line(9, "CHANNELS 7 Zrotation Xrotation Yrotation"),
        "CHANNELS count",
        9,
    ),
    ("short OFFSET", with_line(8, "OFFSET 0 5"), "OFFSET z", 8),
    ("non-numeric OFFSET", with_line(8, "OFFSET 0 five 0"), "OFFSET y", 8),
    ("missing OFFSET", with_line(8, None), "has no OFFSET", 6),
    ("missing CHANNELS", with_line(9, None), "has no CHANNELS", 6),
    ("missing opening brace", with_line(7, None), "expected '{'", 7),
    ("missing closing brace", with_line(13, None), "inside joint 'Hips', found 'MOTION'", 15),
    ("extra closing brace", with_line(15, "}\n}"), "expected 'MOTION'", 16),
    ("missing HIERARCHY", with_line(1, None), "expected 'HIERARCHY'", 1),
    ("missing ROOT", with_line(2, "JOINT Hips"), "expected 'ROOT'", 2),
    ("nameless joint", with_line(6, "JOINT"), "needs a joint name", 6),
    ("duplicate joint name", with_line(6, "JOINT Hips"), "used twice", 6),
    (
        "second root",
        VALID.replace("MOTION", "ROOT Other\n{\nOFFSET 0 0 0\nCHANNELS 0\n}\nMOTION"),
        "second ROOT",
        16,
    ),
    ("missing MOTION", with_line(16, None), "expected 'MOTION'", 16),
    ("text after MOTION", with_line(16, "MOTION now"), "after 'MOTION'", 16),
    ("missing Frames", with_line(17, None), "expected the 'Frames:' line", 17),
    ("missing Frame Time", with_line(18, None), "expected the 'Frame Time:' line", 18),
    ("zero frame time", with_line(18, "Frame Time: 0"), "positive", 18),
    ("negative frame time", with_line(18, "Frame Time: -0.01"), "positive", 18),
    ("non-numeric frame time", with_line(18, "Frame Time: fast"), "must be a number", 18),
    ("tiny frame time", with_line(18, "Frame Time: 1e-320"), "too small", 18),
    ("end of file after MOTION", "\n".join(LINES[:16]) + "\n", "unexpected end of file", 16),
    ("End Site without OFFSET", with_line(12, "}"), "expected 'OFFSET'", 12),
]


@pytest.mark.parametrize("text, fragment, line", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_malformed_file_names_line_and_problem(text: str | bytes, fragment: str, line: int) -> None:
    data = text if isinstance(text, bytes) else text.encode()
    with pytest.raises(BVHError) as info:
        parse_bvh(data, source="case.bvh")
    assert fragment in str(info.value), str(info.value)
    assert info.value.line == line, str(info.value)
    assert str(info.value).startswith(f"case.bvh, line {line}: ")
    assert isinstance(info.value, ValueError)


def test_load_bvh_names_the_file(tmp_path: Path) -> None:
    path = tmp_path / "broken.bvh"
    path.write_text(with_line(20, "1 2"))
    with pytest.raises(BVHError, match=r"broken\.bvh, line 20: frame 2 has 2 values"):
        load_bvh(path)


def test_deep_nesting_does_not_overflow() -> None:
    deep = "HIERARCHY\nROOT R\n{\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n" + "".join(
        f"JOINT J{i}\n{{\nOFFSET 0 1 0\nCHANNELS 1 Zrotation\n" for i in range(3000)
    )
    with pytest.raises(BVHError, match="unexpected end of file"):
        parse_bvh(deep.encode())
    closed = deep + "}\n" * 3001 + "MOTION\nFrames: 1\nFrame Time: 0.1\n" + " ".join(["1"] * 3001) + "\n"
    motion = parse_bvh(closed.encode())
    assert motion.num_joints == 3001 and motion.parents[-1] == 2999


def test_huge_frame_count_fails_before_allocating_the_frames() -> None:
    tracemalloc.start()
    try:
        with pytest.raises(BVHError, match="truncated"):
            parse_bvh(with_line(17, "Frames: 10000000000000000").encode())
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 2**24, f"parsing a file of a few hundred bytes took {peak / 2**20:.0f} MB at its peak"


# --------------------------------------------------------------------------------------- fuzzing

VALID_BYTES = VALID.encode()


@st.composite
def mutated_files(draw: st.DrawFn) -> bytes:
    """VALID after 1-3 random edits: cuts, deletions, insertions of bytes or BVH fragments, byte and
    digit replacements, whitespace changes, duplicated and swapped lines. Positions come from a
    hypothesis-seeded ``Random`` so that they spread over the whole file."""
    rng = draw(st.randoms(use_true_random=False))
    data = VALID_BYTES
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(
            st.sampled_from(
                [
                    "truncate",
                    "delete",
                    "insert",
                    "replace",
                    "digit",
                    "whitespace",
                    "duplicate_line",
                    "swap_lines",
                ]
            )
        )
        i = rng.randint(0, len(data))
        if kind == "truncate":
            data = data[:i]
        elif kind == "delete":
            data = data[:i] + data[i + draw(st.integers(1, 40)) :]
        elif kind == "insert":
            chunk = draw(
                st.one_of(
                    st.binary(min_size=1, max_size=8),
                    st.sampled_from(
                        [
                            b"{",
                            b"}",
                            b" ",
                            b"\n",
                            b"\r\n",
                            b"\t",
                            b"-",
                            b".",
                            b"e",
                            b"1",
                            b"JOINT X\n",
                            b"End Site",
                            b"CHANNELS 1 Xposition",
                            b"OFFSET 1 2 3",
                            b"nan",
                            b"9" * 30,
                        ]
                    ),
                )
            )
            data = data[:i] + chunk + data[i:]
        elif kind in ("replace", "digit", "whitespace"):
            alphabet = {"replace": None, "digit": b"0123456789", "whitespace": b" \t"}[kind]
            spots = [k for k, c in enumerate(data) if alphabet is None or c in alphabet]
            if spots:
                k = rng.choice(spots)
                new = {
                    "replace": bytes([draw(st.integers(0, 255))]),
                    "digit": str(rng.randint(0, 9)).encode(),
                    "whitespace": rng.choice([b"\t", b"  ", b" \t ", b"\r\n"]),
                }[kind]
                data = data[:k] + new + data[k + 1 :]
        else:
            lines = data.split(b"\n")
            a, b = rng.randrange(len(lines)), rng.randrange(len(lines))
            if kind == "duplicate_line":
                lines.insert(b, lines[a])
            else:
                lines[a], lines[b] = lines[b], lines[a]
            data = b"\n".join(lines)
    return data


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated_files())
def test_fuzzed_files_load_or_raise_bvh_error(data: bytes) -> None:
    try:
        motion = parse_bvh(data)
    except BVHError:
        return
    assert isinstance(motion, Motion)
    positions = motion.global_positions()
    assert positions.shape == (motion.num_frames, motion.num_joints, 3)
    assert np.isfinite(motion.rotations.numpy()).all()
