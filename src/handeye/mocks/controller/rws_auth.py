"""Authentication of the mock Robot Web Services (a mixin of
:class:`~handeye.mocks.controller.rws_server.RwsControllerServer`): RWS 1.0's Digest with session
cookies (``-http-session-``, ``ABBCX``), RWS 2.0's Basic; the one user the controller knows."""

from __future__ import annotations

import base64
import hashlib
import secrets
import threading

from .rws_web import HttpError

__all__ = ["RwsAuth", "DEFAULT_USER", "DEFAULT_PASSWORD", "REALM", "split_header"]

DEFAULT_USER, DEFAULT_PASSWORD = "Default User", "robotics"
#: The realm RobotWare's RWS challenges with.
REALM = "validusers@robapi.abb"


class RwsAuth:
    """Who asks: the session of a request, its credentials checked (see the module docstring)."""

    # what the mixin uses of the server (set in RwsControllerServer.__init__)
    sessions: dict[str, dict]
    nonces: set[str]
    username: str
    password: str
    generation: int
    _lock: threading.RLock

    def _session_of(self, handler) -> str | None:
        cookies = handler.headers.get("Cookie", "")
        for part in cookies.split(";"):
            name, _, value = part.strip().partition("=")
            if name == "-http-session-" and value in self.sessions:
                return value
        return None

    def _authenticate(self, handler, method: str) -> tuple[str, dict]:
        """The session of the request (a new one after a good login); 401 otherwise."""
        session = self._session_of(handler)
        if session is not None:
            return session, {}
        header = handler.headers.get("Authorization", "")
        if self._credentials_ok(header, method):
            session = secrets.token_hex(12)
            with self._lock:
                self.sessions[session] = {"user": self.username, "rmmp": "none", "rmmp_asked": False}
            return session, {"Set-Cookie": [f"-http-session-={session}; Path=/; HttpOnly",
                                            f"ABBCX={secrets.token_hex(6)}; Path=/"]}
        if self.generation == 1:
            nonce = secrets.token_hex(16)
            self.nonces.add(nonce)
            challenge = f'Digest realm="{REALM}", nonce="{nonce}", qop="auth", algorithm=MD5'
        else:
            challenge = f'Basic realm="{REALM}"'
        raise HttpError(401, "Unauthorized: wrong user name or password" if header else "Unauthorized",
                        headers={"WWW-Authenticate": challenge})

    def _credentials_ok(self, header: str, method: str) -> bool:
        scheme, _, rest = header.partition(" ")
        if self.generation == 2:
            if scheme.lower() != "basic":
                return False
            try:
                user, _, password = base64.b64decode(rest).decode("utf-8").partition(":")
            except (ValueError, UnicodeDecodeError):
                return False
            return user == self.username and password == self.password
        if scheme.lower() != "digest":
            return False
        fields = {}
        for item in split_header(rest):
            name, _, value = item.partition("=")
            fields[name.strip().lower()] = value.strip().strip('"')
        if fields.get("username") != self.username or fields.get("nonce") not in self.nonces:
            return False
        md5 = lambda text: hashlib.md5(text.encode("utf-8")).hexdigest()  # noqa: E731 - RFC 2617 names
        ha1 = md5(f"{self.username}:{REALM}:{self.password}")
        ha2 = md5(f"{method}:{fields.get('uri', '')}")
        expected = md5(f"{ha1}:{fields['nonce']}:{fields.get('nc', '')}:{fields.get('cnonce', '')}:{fields.get('qop', '')}:{ha2}")
        return secrets.compare_digest(expected, fields.get("response", ""))


def split_header(text: str) -> list[str]:
    """Comma-separated ``name=value`` items of an Authorization header (commas inside quotes kept)."""
    items, current, quoted = [], "", False
    for ch in text:
        if ch == '"':
            quoted = not quoted
        if ch == "," and not quoted:
            items.append(current)
            current = ""
        else:
            current += ch
    if current.strip():
        items.append(current)
    return items
