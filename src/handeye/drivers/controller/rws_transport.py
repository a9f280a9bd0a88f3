"""The transport of the ``rws`` back end below HTTP: the request pacing (a token bucket below the
controller's documented ceiling), TLS with the controller's self-signed certificate pinned by its
SHA-256 fingerprint, closing a session's sockets now, and the one-line reason of a failed request."""

from __future__ import annotations

import re
import threading
import time
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import requests
    from requests.adapters import HTTPAdapter

__all__ = ["RateLimiter", "pinned_adapter", "close_session", "failure_reason"]


class RateLimiter:
    """A token bucket: at most ``rate`` requests per second on average, bursts of ``burst``."""

    def __init__(self, rate: float, burst: int = 10):
        self.rate, self.burst = float(rate), float(burst)
        self.tokens, self.stamp = float(burst), time.monotonic()
        self._lock = threading.Lock()

    def wait(self) -> None:
        with self._lock:
            now = time.monotonic()
            self.tokens = min(self.burst, self.tokens + (now - self.stamp) * self.rate)
            self.stamp = now
            if self.tokens < 1.0:
                pause = (1.0 - self.tokens) / self.rate
                time.sleep(pause)
                self.stamp = time.monotonic()
                self.tokens = 1.0
            self.tokens -= 1.0


def close_session(http: requests.Session) -> None:
    """Close a requests session and its sockets now: urllib3 2 leaves the pools of a cleared
    PoolManager to the garbage collector, which may keep a socket open long after a dropped link."""
    for adapter in http.adapters.values():
        pools = getattr(getattr(adapter, "poolmanager", None), "pools", None)
        if pools is None:
            continue
        for key in list(pools.keys()):
            try:
                pools[key].close()
            except KeyError:
                pass
    http.close()


def failure_reason(exc: BaseException) -> str:
    """The innermost reason of a requests/urllib3 error, one line."""
    text = str(exc)
    m = re.search(r"\((?:Caused by )?\w+\((.*)\)\)\)?$", text)
    text = m.group(1) if m else text
    return re.sub(r"\s+", " ", text)[:200]


def pinned_adapter(fingerprint: str) -> HTTPAdapter:
    """A requests adapter that accepts exactly the certificate of SHA-256 ``fingerprint`` (self-signed)."""
    from requests.adapters import HTTPAdapter

    class PinnedAdapter(HTTPAdapter):
        def init_poolmanager(self, *args, **kwargs):
            kwargs["assert_fingerprint"] = fingerprint
            kwargs["cert_reqs"] = "CERT_NONE"
            kwargs["assert_hostname"] = False
            super().init_poolmanager(*args, **kwargs)

        def cert_verify(self, conn, url, verify, cert):
            super().cert_verify(conn, url, False, cert)
            conn.assert_fingerprint = fingerprint

    return PinnedAdapter()
