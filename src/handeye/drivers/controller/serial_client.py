"""The ``serial`` back end: the line protocol over a serial channel (controllers without PC Interface).

Uses pyserial: ``url`` is a device (``/dev/ttyUSB0``, ``COM3``) or any pyserial URL, e.g.
``socket://127.0.0.1:1026`` for a serial-to-Ethernet converter or the mock controller.

Opening the line starts with a line break and a PING whose reply ends the flush: whatever an
earlier PC left on the line (an unfinished request, late replies) never mixes with ours.
"""

from __future__ import annotations

from typing import Any

from .errors import InvalidRequest
from .interface import Deadline, LinkDown
from .line_client import LineBuffer, LineController, LineTransport

__all__ = [
    "SerialController",
]


class _SerialTransport(LineTransport):
    shared_line = True  # a serial line has no connections: see LineController._flush_line

    def __init__(self, url: str, baudrate: int, timeout_error, protocol_error):
        self.url, self.baudrate = url, baudrate
        self.port = None
        self.buffer = LineBuffer(protocol_error)
        self.timeout_error = timeout_error

    def open(self, deadline: Deadline) -> None:
        import serial

        try:
            port = serial.serial_for_url(self.url, do_not_open=True, baudrate=self.baudrate,
                                         timeout=max(deadline.remaining(), 1e-3), write_timeout=max(deadline.remaining(), 1e-3))
            port.open()
        except (serial.SerialException, OSError, ValueError) as exc:
            raise LinkDown(f"cannot open {self.url}: {exc}") from None
        self.port = port
        self.buffer.clear()

    @property
    def is_open(self) -> bool:
        return self.port is not None and self.port.is_open

    def close(self) -> None:
        if self.port is not None:
            port, self.port = self.port, None
            try:
                port.close()
            except Exception:
                pass

    def write(self, data: bytes, deadline: Deadline) -> None:
        import serial

        if self.port is None:
            raise LinkDown("not open")
        try:
            self.port.write_timeout = max(deadline.remaining(), 1e-3)
            self.port.write(data)
        except serial.SerialTimeoutException:
            raise self.timeout_error(f"writing to {self.url} timed out") from None
        except (serial.SerialException, OSError) as exc:
            raise LinkDown(f"writing to {self.url} failed: {exc}") from None

    def read_line(self, deadline: Deadline) -> bytes:
        import serial

        while True:
            line = self.buffer.take_line()
            if line is not None:
                return line
            left = deadline.remaining()
            if self.port is None:
                raise LinkDown("not open")
            if left <= 0:
                raise self.timeout_error(self.buffer.timeout_text())
            try:
                self.port.timeout = left
                chunk = self.port.read(1)
                while chunk and not chunk.endswith(b"\n") and self.port.in_waiting:
                    more = self.port.read(self.port.in_waiting)
                    if not more:
                        break
                    chunk += more
            except (serial.SerialException, OSError) as exc:
                raise LinkDown(f"reading {self.url} failed: {exc}") from None
            if not chunk:
                raise self.timeout_error(self.buffer.timeout_text())
            self.buffer.feed(chunk)


class SerialController(LineController):
    """The RAPID serial-channel program.

    Parameters
    ----------
    url : str
        Serial device or pyserial URL (``socket://host:port`` for the mock controller).
    baudrate : int
        Default 9600 (set the same on the controller's channel).
    **options
        See :class:`~handeye.drivers.controller.interface.Controller`.
    """

    protocol = "serial"

    def __init__(self, url: str, baudrate: int = 9600, **options: Any):
        if not isinstance(url, str) or not url:
            raise InvalidRequest(f"serial url must be a device path or pyserial URL; got {url!r}")
        if isinstance(baudrate, bool) or not isinstance(baudrate, int) or baudrate <= 0:
            raise InvalidRequest(f"baudrate must be a positive integer; got {baudrate!r}")
        self.url, self.baudrate = url, baudrate
        super().__init__(**options)

    @property
    def address(self) -> str:
        return self.url

    def _make_transport(self) -> LineTransport:
        return _SerialTransport(self.url, self.baudrate, self.timeout_error, self.protocol_error)
