"""An input's first bytes, and the inputs they already show are not a log of poses.

Every importer reads its files through :func:`common.read_text`, and format detection looks at the
files' heads: both refuse here, from the first :data:`~handeye.base.files.HEAD_BYTES` (64 KB),
an empty file, a binary one (named when its first bytes say what it is: an image, an archive, a ROS
bag) and a large text without a single number, in one line that says what is wrong and what to give
instead. A 50 MB image given by mistake is never read whole.
"""

from __future__ import annotations

from pathlib import Path

from ...base import SessionError
from ...base import HEAD_BYTES, binary_offset, check_regular_file, read_file_bytes

__all__ = ["read_head", "check_log_head", "head_text"]

#: First bytes of the binary files most often given by mistake: what the file is, what to do.
_SIGNATURES = (
    (b"\x89PNG", "a PNG image", "give the log of poses itself"),
    (b"\xff\xd8\xff", "a JPEG image", "give the log of poses itself"),
    (b"II*\x00", "a TIFF image", "give the log of poses itself"),
    (b"MM\x00*", "a TIFF image", "give the log of poses itself"),
    (b"%PDF", "a PDF document", "give the log of poses itself"),
    (b"PK\x03\x04", "a ZIP archive", "unpack it and give the log inside"),
    (b"\x1f\x8b", "a gzip archive", "unpack it and give the log inside"),
    (b"7z\xbc\xaf", "a 7-Zip archive", "unpack it and give the log inside"),
    (b"#ROSBAG", "a ROS 1 bag", "export the pose topics to CSV first (rostopic echo -b BAG -p TOPIC)"),
    (b"SQLite format 3\x00", "an SQLite database (a ROS 2 bag?)",
     "export the pose topics to CSV first (ros2 bag, or rosbags-convert)"),
)


def read_head(path, size: int = HEAD_BYTES) -> bytes:
    """The first ``size`` bytes of an input (a folder, named pipe or device, or a file over
    :data:`~handeye.base.files.MAX_FILE_BYTES`, is refused in one line)."""
    missing = f"{path}: no such file"
    check_regular_file(path, "input file", SessionError, missing=missing)
    return read_file_bytes(path, "input file", SessionError, missing=missing, head=size)


def check_log_head(path, head: bytes, size: int = HEAD_BYTES) -> None:
    """Refuse, in one line, an input whose first bytes already show it is not a log of poses.

    Parameters
    ----------
    path : str or Path
        For the message.
    head : bytes
        The file's first ``size`` bytes (all of it when shorter).
    size : int
        How many bytes were asked for: a head that long is only part of the file.

    Raises
    ------
    SessionError
        The file is empty, binary (NUL bytes or a known binary signature), or ``size`` bytes of text
        without a single digit.
    """
    if not head:
        raise SessionError(f"{path} is empty: give the log itself (the file the tool wrote its poses into)")
    for signature, kind, advice in _SIGNATURES:
        if head.startswith(signature):
            raise SessionError(f"{path} is {kind}, not a text log: {advice}")
    offset = binary_offset(head)
    if offset is not None:
        raise SessionError(f"{path} is binary (byte 0x00 at offset {offset}), not a text log: give the log itself")
    if len(head) >= size and not any(48 <= b <= 57 for b in head):
        raise SessionError(f"{path} holds no number in its first {size // 1024} KB: not a log of poses; give the "
                           f"log itself")


def head_text(path, size: int = 4096, strict: bool = True) -> str:
    """The first ``size`` bytes of an input as text (undecodable bytes replaced).

    ``strict``: refuse the input first when its head shows it is not a log (:func:`check_log_head`
    on the first :data:`HEAD_BYTES`); a folder's other files (images, notes) are looked at with
    ``strict`` False.
    """
    if strict:
        head = read_head(path)
        check_log_head(Path(path), head)
        return head[:size].decode("utf-8", errors="replace")
    return read_file_bytes(path, "input file", SessionError, missing=f"{path}: no such file",
                           head=size).decode("utf-8", errors="replace")
