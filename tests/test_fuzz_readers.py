"""Fuzzing the readers of every input the package takes: whatever the bytes on disk, a reader either
returns or raises one of the package's ``HandEyeError`` subclasses with a one-line message. Any other
exception (``ValueError``, ``TypeError``, ``OverflowError``, ``RecursionError``, ``UnicodeDecodeError``,
``IsADirectoryError``, ...) fails the test, and so do a numpy ``RuntimeWarning`` (it would print
before the message) and a hang (named pipes are among the inputs).

Inputs are near-valid documents with a few values replaced (wrong types, NaN/inf, 1e300, integers of
hundreds of digits, wrong shapes, missing or unknown keys), documents with raw YAML/JSON snippets
spliced in (impossible dates, deep nesting, aliases, tags), random bytes inserted into valid files
(invalid UTF-8, UTF-16, NUL bytes), and folders, named pipes or nothing where a file is expected.

The counts per test (``*_CASES``) add up to more than 10,000 generated cases per run; each test checks
that its generated cases really ran.

A case is drawn by hypothesis as one seeded ``random.Random`` (and a few choices of kind and options),
from which the document, its edits and its values come: reproducible like any hypothesis case, at
a fraction of the cost of dozens of strategy draws per value.
"""

from __future__ import annotations

import copy
import json
import os
import shutil
import struct
import tempfile
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from handeye.base.errors import HandEyeError
from handeye.calibration.session import read_session
from handeye.station.config.station import EXAMPLE_FILE, load_config
from handeye.station.importers import (
    read_any,
    read_easy_handeye,
    read_log,
    read_moveit,
    read_opencv,
    read_plain,
    read_stream,
    read_visp,
)
from handeye.station.report.quality import load_thresholds

#: A reader's numpy warning (an overflow in a norm, say) would print before its one-line message: here it fails.
pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")

SESSION_CASES = 2500
CONFIG_CASES = 1500
THRESHOLD_CASES = 1200
MOVEIT_CASES = 700
PLAIN_CSV_CASES = 800
PLAIN_JSON_CASES = 700
STREAM_CASES = 600
EASY_HANDEYE_CASES = 700
VISP_CASES = 500
OPENCV_CASES = 500
DETECT_CASES = 800
LOG_CASES = 700
TOTAL_CASES = (SESSION_CASES + CONFIG_CASES + THRESHOLD_CASES + MOVEIT_CASES + PLAIN_CSV_CASES + PLAIN_JSON_CASES
               + STREAM_CASES + EASY_HANDEYE_CASES + VISP_CASES + OPENCV_CASES + DETECT_CASES + LOG_CASES)


def fuzz_settings(cases: int):
    return settings(max_examples=cases, deadline=None, database=None, print_blob=True,
                    suppress_health_check=list(HealthCheck))


def test_the_fuzz_run_is_at_least_ten_thousand_cases():
    assert TOTAL_CASES >= 10_000


#: Longest acceptable message: room for a long path and a 4000-digit number, not for an expanded alias bomb.
MAX_MESSAGE = 10_000


def expect_only_handeye_errors(read, *args, **kwargs):
    """Call ``read``; a ``HandEyeError`` must carry one non-empty line of sane length, anything else fails."""
    try:
        read(*args, **kwargs)
    except HandEyeError as exc:
        message = str(exc)
        assert message and "\n" not in message and "\r" not in message, repr(message[:500])
        assert len(message) <= MAX_MESSAGE, f"a message of {len(message)} characters: {message[:300]}"


# --------------------------------------------------------------------------- values and documents

#: The values that break naive numeric code, and the rest of a document's scalars. A case's values
#: come from one seeded ``random.Random`` drawn by hypothesis (``CHOICES``, below), as its structural
#: choices do: a recursive hypothesis strategy cost dozens of draws per value and was most of this
#: file's time. (Only immutable values are returned as shared objects: the edits below change drawn
#: lists in place.)
HUGE_INT_VALUES = [10**400, -(10**400), 2**64, -(2**63) - 1, 10**4000]
ODD_FLOAT_VALUES = [1e300, -1e300, 1e-300, 5e-324, 1e7 + 1, -0.0, 720.0001, 1e6]
#: Floats at the edges of the format, as hypothesis' own float strategy favours them.
EDGE_FLOATS = [0.0, -0.0, 1.0, -1.0, 0.5, float("nan"), float("inf"), -float("inf"), 5e-324, -5e-324,
               2.2250738585072014e-308, 1.7976931348623157e308, -1.7976931348623157e308, 2.0**53, 2.0**53 + 2,
               1.1920929e-07, 65504.0, 3.4028235e38]
ODD_STRINGS = ["1e-3", "nan", "inf", "1e400", "abc", "", "0x1f", "1_000", "²"]
#: ``BOMB`` becomes a YAML alias bomb in the YAML documents: 9 ** 8 references to one list in 200 bytes.
BOMB = "__alias_bomb__"
ODD_SPECIALS = [float("nan"), float("inf"), -float("inf"), True, "1e300", "nan", None, BOMB]
KEY_WORDS = ["index", "data", "quality", "postures"]


def random_float(rnd) -> float:
    """An edge value, a plain number, one of any magnitude, or any 64-bit pattern (NaNs included)."""
    how = rnd.randrange(4)
    if how == 0:
        return rnd.choice(EDGE_FLOATS)
    if how == 1:
        return rnd.uniform(-2000.0, 2000.0)
    if how == 2:
        return rnd.choice([-1.0, 1.0]) * 10.0 ** rnd.uniform(-320.0, 308.0)
    return struct.unpack("<d", rnd.randbytes(8))[0]


def random_scalar(rnd):
    """A document scalar: None, a boolean, an integer (small or hundreds of digits), a float, text."""
    how = rnd.randrange(8)
    if how == 0:
        return None
    if how == 1:
        return rnd.random() < 0.5
    if how == 2:
        return rnd.randint(-10**6, 10**6)
    if how == 3:
        return rnd.choice(HUGE_INT_VALUES)
    if how == 4:
        return random_float(rnd)
    if how == 5:
        return rnd.choice(ODD_FLOAT_VALUES)
    if how == 6:
        return _random_text(rnd, 0, 12, surrogates=False)
    return rnd.choice(ODD_STRINGS)


def random_key(rnd):
    """A mapping key: short text, a small integer or one of the documents' own words."""
    how = rnd.randrange(3)
    if how == 0:
        return _random_text(rnd, 0, 10, surrogates=False)
    if how == 1:
        return rnd.randint(-3, 3)
    return rnd.choice(KEY_WORDS)


def random_value(rnd, leaves: int = 12):
    """A scalar, or lists (up to 6 items) and mappings (up to 4 keys) of them, up to ``leaves`` scalars."""
    if leaves <= 1 or rnd.random() < 0.45:
        return random_scalar(rnd)
    mapping = rnd.random() < 0.5
    size = rnd.randint(0, 4 if mapping else 6)
    budget = max(1, (leaves - 1) // max(size, 1))
    if mapping:
        return {random_key(rnd): random_value(rnd, budget) for _ in range(size)}
    return [random_value(rnd, budget) for _ in range(size)]


def random_odd_number(rnd):
    """What a number in a document is most often replaced by: the values that break naive numeric code."""
    how = rnd.randrange(5)
    if how == 0:
        return rnd.choice(HUGE_INT_VALUES)
    if how == 1:
        return rnd.choice(ODD_FLOAT_VALUES)
    if how == 2:
        return rnd.choice(ODD_SPECIALS)
    return [] if how == 3 else [1.0]


def random_replacement(rnd):
    """What a replaced value becomes: an odd number or any value (half and half)."""
    return random_odd_number(rnd) if rnd.random() < 0.5 else random_value(rnd)


def alias_bomb(name: str, levels: int = 8) -> str:
    """A flow sequence of ``9 ** levels`` references to one list, its anchors named ``<name><level>``."""
    text = f"&{name}0 [1, 2, 3, 4, 5, 6, 7, 8, 9]"
    for k in range(1, levels):
        text = f"&{name}{k} [{text}, " + ", ".join([f"*{name}{k - 1}"] * 8) + "]"
    return text


#: The choices of a case (where to edit, what to splice, the values put there) come from one seeded
#: ``random.Random`` per case, drawn by hypothesis (so a run is as reproducible as before).
CHOICES = st.randoms(use_true_random=True)
#: Any document value (``random_value``): one hypothesis draw.
VALUES = CHOICES.map(random_value)


def mutate(rnd, base, steps: int = 3):
    """``base`` with up to ``steps`` random edits: a value replaced, a key or item dropped or added."""
    value = copy.deepcopy(base)
    for _ in range(rnd.randint(0, steps)):
        value = _edit(rnd, value, depth=0)
    return value


@st.composite
def mutated(draw, base, steps: int = 3):
    """:func:`mutate` as a strategy (one draw: the case's ``random.Random``)."""
    return mutate(draw(CHOICES), base, steps)


EDITS = ["descend", "descend", "replace", "drop", "add"]


def _edit(rnd, value, depth):
    if isinstance(value, dict) and value and depth < 6 and rnd.randint(0, 4):
        key = rnd.choice(sorted(value, key=repr))
        action = rnd.choice(EDITS)
        if action == "descend":
            value[key] = _edit(rnd, value[key], depth + 1)
        elif action == "replace":
            value[key] = random_replacement(rnd)
        elif action == "drop":
            del value[key]
        else:
            value[random_key(rnd)] = random_replacement(rnd)
        return value
    if isinstance(value, list) and value and depth < 6 and rnd.randint(0, 4):
        i = rnd.randint(0, len(value) - 1)
        action = rnd.choice(EDITS)
        if action == "descend":
            value[i] = _edit(rnd, value[i], depth + 1)
        elif action == "replace":
            value[i] = random_replacement(rnd)
        elif action == "drop":
            del value[i]
        else:
            value.insert(i, random_replacement(rnd))
        return value
    return random_replacement(rnd)


#: Raw text the serialisers never write but a hand (or another tool) may: each breaks some parser.
SNIPPETS = [
    "2020-13-45", "1" * 5000, "[" * 3000, "{" * 3000, "!!binary AAAA", "!!python/object:os.system {}",
    "!!float abc", "0x" + "f" * 4500, "&a [1, *a]", "*nowhere", "1:2:3", "~", ".nan", "-.inf", "1e400",
    "!!set {a, b}", "!!timestamp 2001-02-30", "? [a, b]\n: c", "%YAML:1.0", "\t", "\x00", "\ufeff",
    "'unclosed", '"\\ud800"', "<<: *x", "- - - -", "\u2028", "NaN", "Infinity", "1" * 400, "-" * 5000,
]


def _random_text(rnd, low: int, high: int, *, surrogates: bool = True) -> str:
    """``low``-``high`` characters from anywhere in Unicode (ASCII, the BMP, the astral planes); lone
    surrogates too, unless ``surrogates`` is false (text a serialiser must write: hypothesis' own text
    strategy never draws them either)."""
    top = rnd.choice([0x7F, 0xFFFF, 0x10FFFF])
    chars = [rnd.randint(0, top) for _ in range(rnd.randint(low, high))]
    if not surrogates:
        chars = [c if not 0xD800 <= c <= 0xDFFF else c - 0x800 for c in chars]
    return "".join(map(chr, chars))


def spoiled_text(rnd, text: str) -> str:
    """``text``, or ``text`` with a snippet or random characters spliced in, or cut short."""
    how = rnd.choice(["keep", "keep", "snippet", "chars", "cut"])
    if how == "keep" or not text:
        return text
    at = rnd.randint(0, len(text))
    if how == "snippet":
        return text[:at] + rnd.choice(SNIPPETS) + text[at:]
    if how == "chars":
        return text[:at] + _random_text(rnd, 1, 8) + text[at:]
    return text[:at]


def spoiled_bytes(rnd, text: str) -> bytes:
    """The bytes of a file holding ``text``: mostly UTF-8, sometimes with foreign bytes or re-encoded."""
    how = rnd.choice(["utf8", "utf8", "utf8", "insert", "utf16", "latin1", "random", "bom"])
    if how == "utf16":
        return text.encode("utf-16", errors="surrogatepass")
    if how == "latin1":
        return text.encode("latin-1", errors="replace") + b"\xe9\xff"
    if how == "random":
        return rnd.randbytes(rnd.randint(0, 300))
    data = text.encode("utf-8", errors="surrogatepass")
    if how == "bom":
        return b"\xef\xbb\xbf" + data
    if how == "insert":
        at = rnd.randint(0, len(data))
        return data[:at] + rnd.randbytes(rnd.randint(1, 8)) + data[at:]
    return data


def spoiled(rnd, text: str) -> bytes:
    """The bytes of a file holding ``text``, spoiled as text and then as bytes."""
    return spoiled_bytes(rnd, spoiled_text(rnd, text))


@st.composite
def file_bodies(draw, documents):
    """Bytes of a file: a document (drawn from ``documents``), :func:`spoiled`."""
    text = draw(documents)
    return spoiled(draw(CHOICES), text)


_DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)


def yaml_text(value) -> str:
    parts = yaml.dump(value, Dumper=_DUMPER, sort_keys=False, allow_unicode=True, default_flow_style=None).split(BOMB)
    return parts[0] + "".join(alias_bomb(f"b{k}_") + part for k, part in enumerate(parts[1:]))


def json_text(value) -> str:
    return json.dumps(value)


#: Where a file is expected: usually a file, sometimes a folder, a named pipe or nothing.
KIND_NAMES = ["file"] * 12 + ["folder", "fifo", "missing"]
KINDS = st.sampled_from(KIND_NAMES)


def put(path: Path, kind: str, body: bytes) -> None:
    if kind == "file":
        path.write_bytes(body)
    elif kind == "folder":
        path.mkdir()
        (path / "inside.yaml").write_text("a: 1\n")
    elif kind == "fifo":
        os.mkfifo(path)


#: Scratch folders live in memory when the system has a tmpfs there: creating and removing thousands
#: of folders on a disk file system costs milliseconds each and would dominate the run.
SCRATCH_BASE = "/dev/shm" if os.path.isdir("/dev/shm") and os.access("/dev/shm", os.W_OK) else None


class Scratch:
    """A fresh temporary folder per generated case (hypothesis cannot use pytest's ``tmp_path`` per case)."""

    def __enter__(self) -> Path:
        self.path = Path(tempfile.mkdtemp(prefix="handeye-fuzz-", dir=SCRATCH_BASE))
        return self.path

    def __exit__(self, *exc):
        shutil.rmtree(self.path, ignore_errors=True)


def run_counted(check, cases: int) -> None:
    """Run a hypothesis test and check that it really generated ``cases`` cases."""
    ran = []
    check(ran)
    assert len(ran) >= cases, f"only {len(ran)} of {cases} cases ran"


# --------------------------------------------------------------------------- sessions

GOOD_POSE = {"position_mm": [812.4, -120.3, 903.1], "quaternion_wxyz": [0.0, 0.7071068, 0.7071068, 0.0]}
GOOD_POSTURE = {
    "index": 0,
    "tool0_in_base": GOOD_POSE,
    "joints_deg": [0.0, 10.0, 20.0, 0.0, 30.0, 0.0],
    "points_mm": [[-15.0, -15.0, 900.0], [15.0, -15.0, 900.0], [-15.0, 15.0, 900.0], [15.0, 15.0, 900.0],
                  [-15.0, 45.0, 900.0], [15.0, 45.0, 900.0]],
    "target_in_camera": {"position_mm": [-15.0, -15.0, 900.0], "quaternion_wxyz": [1.0, 0.0, 0.0, 0.0]},
    "quality": {"plane_rms_mm": 0.1},
}
GOOD_HEADER = {"format": "handeye-session/1", "setup": "eye_in_hand", "robot": "IRB1400",
               "target": {"type": "checkerboard", "corners": [2, 3], "square_mm": 30.0}}
ODD_POSTURE_NAMES = ["²³.yaml", "٣.yaml", "-1.yaml", "99999999999999999999.yaml", " 7.yaml"]


def posture_name(rnd) -> str:
    """A posture file's name: numbered as the writer numbers them, other characters, or odd digits."""
    how = rnd.randrange(3)
    if how == 0:
        return f"{rnd.randint(0, 1200):03d}.yaml"
    if how == 1:
        return "".join(rnd.choice("0123456789abc._-") for _ in range(rnd.randint(1, 6))) + ".yaml"
    return rnd.choice(ODD_POSTURE_NAMES)


def posture_body(rnd) -> bytes:
    """A posture file: an edited good posture, a good one with another index, or any value."""
    how = rnd.randrange(3)
    if how == 0:
        text = yaml_text(mutate(rnd, GOOD_POSTURE, steps=4))
    elif how == 1:
        text = yaml_text({**GOOD_POSTURE, "index": rnd.randint(0, 1200)})
    else:
        text = yaml_text(random_value(rnd))
    return spoiled(rnd, text)


@st.composite
def session_folders(draw):
    """``(header kind, header bytes, postures kind, [(name, kind, bytes)] up to 3 distinct names, truth?)``."""
    rnd = draw(CHOICES)
    header_kind = rnd.choice(KIND_NAMES)
    header = yaml_text(mutate(rnd, GOOD_HEADER) if rnd.random() < 0.5 else random_value(rnd))
    header = spoiled(rnd, header)
    postures_kind = rnd.choice(["folder"] * 8 + ["file", "missing"])
    postures = {}
    for _ in range(rnd.randint(0, 3)):
        name = posture_name(rnd)
        if name not in postures:
            postures[name] = (name, rnd.choice(KIND_NAMES), posture_body(rnd))
    return header_kind, header, postures_kind, list(postures.values()), rnd.random() < 0.5


def test_read_session_raises_only_handeye_errors():
    def check(ran):
        @fuzz_settings(SESSION_CASES)
        @given(session_folders())
        def case(spec):
            ran.append(1)
            header_kind, header, postures_kind, postures, with_truth = spec
            with Scratch() as root:
                put(root / "session.yaml", header_kind, header)
                folder = root / "postures"
                if postures_kind == "file":
                    folder.write_text("not a folder\n")
                elif postures_kind == "folder":
                    folder.mkdir()
                    for name, kind, body in postures:
                        put(folder / name, kind, body)
                if with_truth:
                    (root / "truth.yaml").write_bytes(header)
                expect_only_handeye_errors(read_session, root)
                from handeye.calibration.session import read_truth

                expect_only_handeye_errors(read_truth, root)

        case()

    run_counted(check, SESSION_CASES)


# --------------------------------------------------------------------------- station config and thresholds

EXAMPLE_CONFIG = yaml.safe_load(EXAMPLE_FILE.read_text())
GOOD_THRESHOLDS = {"max_d_org_mm": 1.0, "max_posture_residual_mm": 2.0, "max_sigma_translation_mm": 0.2,
                   "max_sigma_rotation_deg": 0.02, "min_inlier_postures": 12, "max_outlier_fraction": 0.2,
                   "min_rotation_axis_spread_deg": 10.0, "min_median_rotation_deg": 15.0}


def test_load_config_raises_only_handeye_errors():
    documents = st.one_of(mutated(EXAMPLE_CONFIG, steps=4).map(yaml_text), VALUES.map(yaml_text),
                          st.just(EXAMPLE_FILE.read_text()))

    def check(ran):
        @fuzz_settings(CONFIG_CASES)
        @given(KINDS, file_bodies(documents))
        def case(kind, body):
            ran.append(1)
            with Scratch() as root:
                put(root / "station.yaml", kind, body)
                expect_only_handeye_errors(load_config, root / "station.yaml")

        case()

    run_counted(check, CONFIG_CASES)


def test_load_thresholds_raises_only_handeye_errors():
    documents = st.one_of(mutated(GOOD_THRESHOLDS).map(yaml_text),
                          mutated({"robot": "IRB1400", "quality": GOOD_THRESHOLDS}).map(yaml_text),
                          VALUES.map(yaml_text))

    def check(ran):
        @fuzz_settings(THRESHOLD_CASES)
        @given(KINDS, file_bodies(documents))
        def case(kind, body):
            ran.append(1)
            with Scratch() as root:
                put(root / "thresholds.yaml", kind, body)
                expect_only_handeye_errors(load_thresholds, root / "thresholds.yaml")

        case()

    run_counted(check, THRESHOLD_CASES)


# --------------------------------------------------------------------------- importers

def _matrix(x=0.5, y=-0.2, z=0.9):
    return [[1.0, 0.0, 0.0, x], [0.0, 0.0, -1.0, y], [0.0, 1.0, 0.0, z], [0.0, 0.0, 0.0, 1.0]]


COMMON_OPTIONS = st.fixed_dictionaries({}, optional={
    "setup": st.sampled_from(["eye_in_hand", "eye_to_hand", "bogus"]),
    "units": st.sampled_from(["m", "mm", "km"]),
    "skip_invalid": st.booleans(),
})


def _importer_test(read, cases, documents, suffix, options=COMMON_OPTIONS):
    def check(ran):
        @fuzz_settings(cases)
        @given(KINDS, file_bodies(documents), options)
        def case(kind, body, kwargs):
            ran.append(1)
            with Scratch() as root:
                put(root / f"input{suffix}", kind, body)
                expect_only_handeye_errors(read, root / f"input{suffix}", **kwargs)

        case()

    run_counted(check, cases)


MOVEIT = [[_matrix(0.1 * k, 0.2, 0.5), _matrix(0.0, 0.1 * k, 0.8)] for k in range(4)]


def test_read_moveit_raises_only_handeye_errors():
    _importer_test(read_moveit, MOVEIT_CASES,
                   st.one_of(mutated(MOVEIT, steps=4).map(json_text), VALUES.map(json_text)), ".json")


CSV_HEADER = ["index", "tool0_x", "tool0_y", "tool0_z", "tool0_qw", "tool0_qx", "tool0_qy", "tool0_qz",
              "target_x", "target_y", "target_z", "target_qw", "target_qx", "target_qy", "target_qz"]
CSV_WORDS = ["nan", "inf", "1e400", "", "x", "1,5", '"', "1e-3"]


def random_csv_field(rnd, low: float = -2000.0, high: float = 2000.0) -> str:
    """A CSV cell: a number in ``[low, high]`` (the ends, zeros and tiny ones too), a small integer,
    a word that breaks number parsing, or a little text."""
    how = rnd.randrange(4)
    if how == 0:
        if rnd.random() < 0.2:
            return repr(rnd.choice([low, high, 0.0, -0.0, 5e-324, 1e-300]))
        return repr(rnd.uniform(low, high))
    if how == 1:
        return str(rnd.randint(-5, 5))
    if how == 2:
        return rnd.choice(CSV_WORDS)
    return _random_text(rnd, 0, 5, surrogates=False)


@st.composite
def plain_csv(draw):
    rnd = draw(CHOICES)
    how = rnd.randrange(3)
    if how == 0:
        header = list(CSV_HEADER)
    elif how == 1:
        header = rnd.sample(CSV_HEADER, len(CSV_HEADER))
    else:
        header = [rnd.choice(CSV_HEADER + ["q1", "tool0_q1", "extra", ""]) for _ in range(rnd.randint(0, 18))]
    separator = rnd.choice([",", ",", ";", "\t", " "])
    rows = [[random_csv_field(rnd) for _ in range(rnd.randint(max(len(header) - 1, 0), len(header) + 1))]
            for _ in range(rnd.randint(0, 5))]
    lines = [separator.join(header)] + [separator.join(row) for row in rows]
    if rnd.random() < 0.5:
        lines.insert(0, "# exported by a spreadsheet")
    return "\n".join(lines) + "\n"


def test_read_plain_csv_raises_only_handeye_errors():
    options = COMMON_OPTIONS.flatmap(lambda o: st.fixed_dictionaries(
        {}, optional={"quaternion_order": st.sampled_from(["wxyz", "xyzw", "zyxw"])}).map(lambda q: {**o, **q}))
    _importer_test(read_plain, PLAIN_CSV_CASES, plain_csv(), ".csv", options)


PLAIN_JSON = {"setup": "eye_in_hand", "units": "mm", "quaternion_order": "wxyz",
              "target": {"corners": [13, 8], "square_mm": 30.0},
              "postures": [{"index": k, "tool0_in_base": {"position": [800.0, 10.0 * k, 900.0], "quaternion": [1, 0, 0, 0]},
                            "target_in_camera": {"matrix": _matrix(10.0, 20.0 * k, 900.0)}} for k in range(4)]}


def test_read_plain_json_raises_only_handeye_errors():
    _importer_test(read_plain, PLAIN_JSON_CASES,
                   st.one_of(mutated(PLAIN_JSON, steps=4).map(json_text), VALUES.map(json_text)), ".json")


@st.composite
def stream_csv(draw):
    rnd = draw(CHOICES)
    rows = [[random_csv_field(rnd, -10.0, 2000.0) if rnd.random() < 0.5 else random_csv_field(rnd)
             for _ in range(rnd.randint(7, 9))] for _ in range(rnd.randint(0, 8))]
    good = [[f"{1000.0 + 0.1 * k:.3f}", "0.5", f"{0.01 * k}", "0.9", "0", "0", "0", "1"] for k in range(rnd.randint(0, 6))]
    lines = [",".join(r) for r in good + rows]
    if rnd.random() < 0.5:
        lines.insert(0, "t,x,y,z,qx,qy,qz,qw")
    return "\n".join(lines) + "\n"


def test_read_stream_raises_only_handeye_errors():
    options = COMMON_OPTIONS.flatmap(lambda o: st.fixed_dictionaries({}, optional={
        "quaternion_order": st.sampled_from(["wxyz", "xyzw", "bad"]),
        "camera_pose": st.sampled_from(["camera_in_target", "target_in_camera", "bad"]),
        "tolerance_s": st.sampled_from([0.03, 0.0, -1.0, float("nan"), 1e300]),
        "max_postures": st.sampled_from([0, 1, 3, 40, -1]),
        "rest_mm_s": st.sampled_from([None, 1.0, float("inf")]),
        "rest_deg_s": st.sampled_from([None, 1.0, 0.0]),
    }).map(lambda q: {**o, **q}))

    def check(ran):
        @fuzz_settings(STREAM_CASES)
        @given(KINDS, file_bodies(stream_csv()), KINDS, file_bodies(stream_csv()), options)
        def case(kind_a, body_a, kind_b, body_b, kwargs):
            ran.append(1)
            with Scratch() as root:
                put(root / "hand_base_link.csv", kind_a, body_a)
                put(root / "target_camera.csv", kind_b, body_b)
                expect_only_handeye_errors(read_stream, [root / "hand_base_link.csv", root / "target_camera.csv"],
                                           **kwargs)

        case()

    run_counted(check, STREAM_CASES)


def _transform(x, y, z):
    return {"translation": {"x": x, "y": y, "z": z}, "rotation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}


EASY_HANDEYE = {"parameters": {"calibration_type": "eye_in_hand", "robot_base_frame": "base_link"},
                "samples": [{"robot": _transform(0.5, 0.1 * k, 0.9), "tracking": _transform(0.0, 0.05 * k, 0.8)}
                            for k in range(4)]}


def test_read_easy_handeye_raises_only_handeye_errors():
    _importer_test(read_easy_handeye, EASY_HANDEYE_CASES,
                   st.one_of(mutated(EASY_HANDEYE, steps=4).map(yaml_text), VALUES.map(yaml_text)), ".samples")


VISP_VECTOR = {"rows": 6, "cols": 1, "data": [[0.5], [0.1], [0.9], [0.0], [0.1], [0.2]]}
VISP_NAMES = st.one_of(st.integers(0, 5).map(lambda k: f"pose_fPe_{k}.yaml"),
                       st.integers(0, 5).map(lambda k: f"pose_cPo_{k}.yaml"),
                       st.integers(0, 5).map(lambda k: f"franka_pose_rPe_{k}.yaml"),
                       st.integers(0, 3).map(lambda k: f"franka_image-{k}.png"),
                       st.sampled_from(["franka_camera.xml", "chessboard-data.txt", "notes.txt"]))
VISP_BODIES = st.one_of(mutated(VISP_VECTOR).map(lambda v: "%YAML:1.0\n" + yaml_text(v)), VALUES.map(yaml_text),
                        st.just("<root><camera><model><px>600</px><py>600</py><u0>320</u0><v0>240</v0></model>"
                                "</camera></root>"),
                        st.sampled_from(["9 x 6\nsquare size: 0.025 m\n", "99999 x 1\nsquare size: 1.2.3\n", "<"]))


def test_read_visp_raises_only_handeye_errors():
    def check(ran):
        @fuzz_settings(VISP_CASES)
        @given(st.lists(st.tuples(VISP_NAMES, KINDS, file_bodies(VISP_BODIES)), max_size=6, unique_by=lambda t: t[0]),
               COMMON_OPTIONS)
        def case(files, kwargs):
            ran.append(1)
            with Scratch() as root:
                for name, kind, body in files:
                    put(root / name, kind, body)
                expect_only_handeye_errors(read_visp, root, **kwargs)

        case()

    run_counted(check, VISP_CASES)


def _opencv_matrix(values) -> str:
    return "!!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: d\n   data: [ " + ", ".join(values) + " ]\n"


@st.composite
def opencv_storage(draw):
    number = st.one_of(st.floats(-2, 2).map(repr), st.sampled_from(["1.", "0.", ".nan", "1e400", "x", ""]))
    lines = ["%YAML:1.0", "---"]
    if draw(st.booleans()):
        lines.append(f"frameCount: {draw(st.sampled_from(['3', '-1', 'x', '1e400', '99999999999999999999']))}")
    for k in range(draw(st.integers(0, 4))):
        for prefix in draw(st.sampled_from([("T1", "T2"), ("T1",), ("T2", "T1"), ("X1", "T2")])):
            values = [repr(v) for row in _matrix(0.1 * k, 0.2, 0.5) for v in row]
            if draw(st.booleans()):
                values[draw(st.integers(0, 15))] = draw(number)
            if draw(st.integers(0, 5)) == 0:
                values = values[:draw(st.integers(0, 15))]
            lines.append(f"{prefix}_{k}: " + _opencv_matrix(values))
    return "\n".join(lines) + "\n"


def test_read_opencv_raises_only_handeye_errors():
    options = COMMON_OPTIONS.flatmap(lambda o: st.fixed_dictionaries({}, optional={
        "robot_prefix": st.sampled_from(["T1", "X1", ""]), "camera_prefix": st.sampled_from(["T2", "T1"])}).map(
        lambda q: {**o, **q}))
    _importer_test(read_opencv, OPENCV_CASES, opencv_storage(), ".yml", options)


def _pose_row(k: int, width: int) -> list:
    """A plausible pose row of ``width`` numbers (flange ~1 m out, a unit quaternion, angles in degrees)."""
    base = [800.0 + 10 * k, 20.0 * k, 900.0]
    if width == 7:
        return base + [0.0, 0.7071068, 0.7071068, 0.0]
    if width == 16:
        return sum(_matrix(0.8 + 0.01 * k, 0.02 * k, 0.9), [])
    return base + [10.0 * k, -20.0, 170.0]


@st.composite
def log_text(draw):
    """Text tables as the log reader meets them: widths of one or two poses, index columns, headers,
    separators, blocks, odd values and matrix rows."""
    rnd = draw(CHOICES)
    width = rnd.choice([4, 6, 7, 12, 13, 14, 16, 19, 23, 32, 3, 5, 40])
    lines = []
    if rnd.random() < 0.5:
        lines.append(rnd.choice(["x y z a b c cam_x cam_y cam_z qx qy qz qw", "# robot poses", "index,x,y,z",
                                 "t qw qx qy qz", "camera:"]))
    separator = rnd.choice([",", " ", "\t", ";", "  "])
    for k in range(rnd.randint(0, 8)):
        row = (_pose_row(k, 7) + _pose_row(k, 6) + _pose_row(k, 16) + [1.0] * 40)[:width]
        cells = [repr(v) for v in row]
        if rnd.randint(0, 4) == 0 and cells:
            cells[rnd.randint(0, len(cells) - 1)] = random_csv_field(rnd)
        lines.append(separator.join(cells))
        if rnd.randint(0, 6) == 0:
            lines.append(rnd.choice(["", "# camera", "posture 3:", "0 0 0 1"]))
    return "\n".join(lines) + "\n"


LOG_JSON = {"robot_poses": [_pose_row(k, 6) for k in range(4)],
            "samples": [{"tool": {"position": [0.8, 0.1 * k, 0.9], "orientation": {"x": 0, "y": 0, "z": 0, "w": 1}},
                         "marker": {"rvec": [0.1, 0.2, 3.0], "tvec": [0.0, 0.05 * k, 0.8]}} for k in range(3)],
            "T_cam_target_0": {"rows": 4, "cols": 4, "data": sum(_matrix(), [])}}


def test_read_log_raises_only_handeye_errors():
    documents = st.one_of(log_text(), mutated(LOG_JSON, steps=4).map(json_text), mutated(LOG_JSON, steps=4).map(yaml_text),
                          VALUES.map(json_text), st.text(max_size=200))
    suffixes = st.sampled_from([".csv", ".txt", ".json", ".yaml", ""])
    options = COMMON_OPTIONS.flatmap(lambda o: st.fixed_dictionaries({}, optional={
        "euler": st.sampled_from(["kuka", "ZYX:deg", "robot:xyz", "camera=rotvec", "bogus", "robot:fanuc,camera:ros", ""]),
        "quaternion_order": st.sampled_from(["wxyz", "xyzw", "zyxw"]),
        "robot_pose": st.sampled_from(["flange_in_base", "base_in_flange", "bad"]),
        "camera_pose": st.sampled_from(["target_in_camera", "camera_in_target", "bad"]),
    }).map(lambda q: {**o, **q}))

    def check(ran):
        @fuzz_settings(LOG_CASES)
        @given(KINDS, file_bodies(documents), suffixes, options, st.booleans(), file_bodies(log_text()))
        def case(kind, body, suffix, kwargs, two_files, second):
            ran.append(1)
            with Scratch() as root:
                put(root / f"input{suffix}", kind, body)
                paths = root / f"input{suffix}"
                if two_files:
                    (root / "camera.csv").write_bytes(second)
                    paths = [root / f"input{suffix}", root / "camera.csv"]
                expect_only_handeye_errors(read_log, paths, **kwargs)

        case()

    run_counted(check, LOG_CASES)


def test_read_any_detects_or_raises_only_handeye_errors():
    documents = st.one_of(mutated(MOVEIT).map(json_text), plain_csv(), mutated(PLAIN_JSON).map(json_text),
                          stream_csv(), mutated(EASY_HANDEYE).map(yaml_text), opencv_storage(),
                          VALUES.map(yaml_text), st.text(max_size=200), log_text())
    suffixes = st.sampled_from([".json", ".csv", ".yaml", ".yml", ".samples", ".txt", ""])

    def check(ran):
        @fuzz_settings(DETECT_CASES)
        @given(KINDS, file_bodies(documents), suffixes)
        def case(kind, body, suffix):
            ran.append(1)
            with Scratch() as root:
                put(root / f"input{suffix}", kind, body)
                expect_only_handeye_errors(read_any, root / f"input{suffix}")

        case()

    run_counted(check, DETECT_CASES)


@pytest.mark.parametrize("reader", [read_session, load_config, load_thresholds, read_moveit, read_plain,
                                    read_easy_handeye, read_opencv, read_any, read_log])
def test_named_pipe_inputs_are_refused_without_hanging(tmp_path, reader):
    """The fuzzers draw named pipes among other inputs; this pins it for each reader on its own."""
    pipe = tmp_path / ("session" if reader is read_session else "input.yaml")
    if reader is read_session:
        pipe.mkdir()
        os.mkfifo(pipe / "session.yaml")
    else:
        os.mkfifo(pipe)
    with pytest.raises(HandEyeError, match=r"named pipe \(FIFO\), not a regular file"):
        reader(pipe)
