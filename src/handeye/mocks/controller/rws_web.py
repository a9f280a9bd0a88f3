"""The web server of the mock Robot Web Services: a threading HTTP(S) server whose requests the
controller (:class:`~handeye.mocks.controller.rws_server.RwsControllerServer`) dispatches, its
error answers (:class:`HttpError`) and the self-signed certificate of RWS 2.0 (made once per
process, as an OmniCore controller makes its own)."""

from __future__ import annotations

import hashlib
import logging
import os
import socket
import ssl
import tempfile
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .rws_server import RwsControllerServer

__all__ = ["HttpError", "RwsHandler", "RwsHttpServer", "HAL_JSON", "self_signed_certificate"]

log = logging.getLogger("handeye.mocks.controller.rws_server")

HAL_JSON = "application/hal+json;v=2.0"

_CERT_LOCK = threading.Lock()
_CERT: tuple | None = None


def self_signed_certificate() -> tuple[str, str, str]:
    """``(certificate file, key file, SHA-256 fingerprint)`` of a self-signed certificate for
    127.0.0.1, made once per process (as an OmniCore controller makes its own)."""
    global _CERT
    with _CERT_LOCK:
        if _CERT is None:
            import datetime

            from cryptography import x509
            from cryptography.hazmat.primitives import hashes, serialization
            from cryptography.hazmat.primitives.asymmetric import ec
            from cryptography.x509.oid import NameOID

            key = ec.generate_private_key(ec.SECP256R1())
            name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "handeye mock OmniCore")])
            now = datetime.datetime.now(datetime.timezone.utc)
            cert = (x509.CertificateBuilder().subject_name(name).issuer_name(name).public_key(key.public_key())
                    .serial_number(x509.random_serial_number()).not_valid_before(now - datetime.timedelta(days=1))
                    .not_valid_after(now + datetime.timedelta(days=30)).sign(key, hashes.SHA256()))
            folder = tempfile.mkdtemp(prefix="handeye-rws-")
            cert_file, key_file = os.path.join(folder, "cert.pem"), os.path.join(folder, "key.pem")
            with open(cert_file, "wb") as f:
                f.write(cert.public_bytes(serialization.Encoding.PEM))
            with open(key_file, "wb") as f:
                f.write(key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                          serialization.NoEncryption()))
            fingerprint = hashlib.sha256(cert.public_bytes(serialization.Encoding.DER)).hexdigest()
            _CERT = (cert_file, key_file, fingerprint)
        return _CERT


class HttpError(Exception):
    """An error answer: HTTP status, the controller's code and message."""

    def __init__(self, status: int, message: str, code: int = -1, headers: dict[str, str | list[str]] | None = None):
        super().__init__(message)
        self.status, self.message, self.code, self.headers = status, message, code, headers or {}


class RwsHandler(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"
    server_version = "handeye-mock-RWS"
    disable_nagle_algorithm = True  # headers and body are two writes: no 40 ms Nagle/delayed-ACK stall
    server: RwsHttpServer  # the server that made this handler (socketserver passes it)

    def log_message(self, fmt: str, *args: object) -> None:  # quiet: the test output is ours
        log.debug("mock RWS: " + fmt, *args)

    def setup(self) -> None:
        # typeshed calls timeout a ClassVar; socketserver reads it per instance in setup(): set per connection
        self.timeout = self.server.owner.idle_timeout_s  # pyright: ignore[reportAttributeAccessIssue]
        super().setup()
        self.server.owner._track(self.connection, True)

    def finish(self) -> None:
        try:
            super().finish()
        finally:
            self.server.owner._track(self.connection, False)

    def do_GET(self) -> None:
        self._serve("GET")

    def do_POST(self) -> None:
        self._serve("POST")

    def do_PUT(self) -> None:
        self._serve("PUT")

    def do_DELETE(self) -> None:
        self._serve("DELETE")

    def _serve(self, method: str) -> None:
        owner = self.server.owner
        length = int(self.headers.get("Content-Length") or 0)
        body = self.rfile.read(length) if length else b""
        if owner._fault_before_answer(self):
            self.close_connection = True
            return
        try:
            status, payload, headers = owner.dispatch(self, method, body)
        except HttpError as err:
            status, payload, headers = err.status, owner.error_body(self, err), err.headers
        except Exception as exc:  # a bug in the mock must show, not hang the client
            log.exception("mock RWS: %s %s failed", method, self.path)
            status, payload, headers = 500, owner.error_body(self, HttpError(500, str(exc))), {}
        if owner.faults.take("garbage_next"):
            owner.faults.note("garbage")
            status, payload, headers = 200, (owner.faults.garbage, "application/json"), {}
        self._answer(status, payload, headers)

    def _answer(self, status: int, payload: tuple[bytes, str] | None, headers: dict) -> None:
        data, ctype = payload if payload is not None else (b"", None)
        self.send_response(status)
        for name, value in headers.items():
            for v in value if isinstance(value, list) else [value]:
                self.send_header(name, v)
        if ctype:
            self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(data)))
        self.end_headers()
        if data and self.command != "HEAD":
            self.wfile.write(data)


class RwsHttpServer(ThreadingHTTPServer):
    daemon_threads = False
    block_on_close = True
    allow_reuse_address = True

    def __init__(self, address: tuple[str, int], owner: RwsControllerServer, tls_context: ssl.SSLContext | None = None):
        self.owner, self.tls_context = owner, tls_context
        super().__init__(address, RwsHandler)

    def finish_request(self, request: socket.socket, client_address: tuple[str, int]) -> None:  # a TCP server's
        if self.tls_context is not None:  # the handshake in the connection's own thread
            try:
                request.settimeout(self.owner.idle_timeout_s)
                request = self.tls_context.wrap_socket(request, server_side=True)
            except (OSError, ssl.SSLError) as exc:
                log.info("mock RWS: TLS handshake with %s failed: %s", client_address, exc)
                return
        super().finish_request(request, client_address)

    def handle_error(self, request: socket.socket, client_address: tuple[str, int]) -> None:
        log.debug("mock RWS: connection from %s ended with an error", client_address, exc_info=True)
