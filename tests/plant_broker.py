"""A real mosquitto on 127.0.0.1 for the plant's tests: a password file, an ACL and a TLS listener.

:class:`Broker` writes ``mosquitto.conf`` in a folder with two free ports (plain and TLS), a password
file made by ``mosquitto_passwd``, an ACL that lets each cell write only below its own topic and the
fleet read everything, and a CA with a server certificate for 127.0.0.1 made with ``cryptography``.
Persistence is on (autosaved after every change), so a broker stopped and started again keeps the
fleet's queued messages. ``MOSQUITTO_MISSING`` is the skip reason where mosquitto is not installed.
"""

from __future__ import annotations

import datetime
import ipaddress
import os
import shutil
import signal
import socket
import subprocess
import time
from pathlib import Path

MOSQUITTO = shutil.which("mosquitto") or ("/usr/sbin/mosquitto" if os.path.exists("/usr/sbin/mosquitto") else None)
MOSQUITTO_PASSWD = shutil.which("mosquitto_passwd") or ("/usr/bin/mosquitto_passwd"
                                                         if os.path.exists("/usr/bin/mosquitto_passwd") else None)
MOSQUITTO_MISSING = None if MOSQUITTO and MOSQUITTO_PASSWD else \
    "Debian's mosquitto (and mosquitto_passwd) is not installed: apt-get install mosquitto (.ci/system-deps does)"

PREFIX = "acme/berlin/body/line2"
FLEET_USER, FLEET_PASSWORD = "fleet", "fleet-secret-1"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def cell_user(cell: str) -> tuple[str, str]:
    return cell, f"pw-{cell}-secret"


def make_ca(folder: Path) -> dict:
    """A CA and a server certificate for 127.0.0.1 and localhost (PEM files in ``folder``)."""
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID

    def name(text):
        return x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, text)])

    now = datetime.datetime.now(datetime.timezone.utc)
    ca_key, key = ec.generate_private_key(ec.SECP256R1()), ec.generate_private_key(ec.SECP256R1())
    ca = (x509.CertificateBuilder().subject_name(name("handeye test plant CA")).issuer_name(name("handeye test plant CA"))
          .public_key(ca_key.public_key()).serial_number(x509.random_serial_number())
          .not_valid_before(now - datetime.timedelta(minutes=5)).not_valid_after(now + datetime.timedelta(days=2))
          .add_extension(x509.BasicConstraints(ca=True, path_length=None), critical=True)
          .sign(ca_key, hashes.SHA256()))
    server = (x509.CertificateBuilder().subject_name(name("127.0.0.1")).issuer_name(ca.subject)
              .public_key(key.public_key()).serial_number(x509.random_serial_number())
              .not_valid_before(now - datetime.timedelta(minutes=5)).not_valid_after(now + datetime.timedelta(days=2))
              .add_extension(x509.SubjectAlternativeName([x509.IPAddress(ipaddress.ip_address("127.0.0.1")),
                                                          x509.DNSName("localhost")]), critical=False)
              .sign(ca_key, hashes.SHA256()))
    files = {"ca": folder / "ca.pem", "cert": folder / "server.pem", "key": folder / "server.key"}
    files["ca"].write_bytes(ca.public_bytes(serialization.Encoding.PEM))
    files["cert"].write_bytes(server.public_bytes(serialization.Encoding.PEM))
    files["key"].write_bytes(key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.TraditionalOpenSSL,
                                               serialization.NoEncryption()))
    os.chmod(files["key"], 0o600)
    return files


def acl_text(cells, prefix: str = PREFIX) -> str:
    """The ACL the README documents: each cell writes below its own topic only, the fleet reads all."""
    lines = [f"user {FLEET_USER}", f"topic read {prefix.split('/')[0]}/#", ""]
    for cell in cells:
        lines += [f"user {cell}", f"topic readwrite {prefix}/{cell}/handeye/#", ""]
    return "\n".join(lines)


class Broker:
    """mosquitto in ``folder`` for ``cells`` (their users, passwords and ACL), not started."""

    def __init__(self, folder: Path, cells=("cell01", "cell02")):
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.cells = tuple(cells)
        self.port, self.tls_port = free_port(), free_port()
        self.tls = make_ca(self.folder)
        self._write_users()
        (self.folder / "acl").write_text(acl_text(self.cells))
        (self.folder / "data").mkdir(exist_ok=True)
        self.conf = self.folder / "mosquitto.conf"
        self.conf.write_text(self._conf())
        self.process = None

    def _write_users(self) -> None:
        path = self.folder / "passwd"
        users = [(FLEET_USER, FLEET_PASSWORD)] + [cell_user(cell) for cell in self.cells]
        path.write_text("".join(f"{user}:{password}\n" for user, password in users))
        subprocess.run([MOSQUITTO_PASSWD, "-U", str(path)], check=True, capture_output=True)  # hashes them in place
        os.chmod(path, 0o600)

    def _conf(self) -> str:
        f = self.folder
        return "\n".join([
            *(["user root"] if os.geteuid() == 0 else []),
            "per_listener_settings false", "allow_anonymous false",
            f"password_file {f / 'passwd'}", f"acl_file {f / 'acl'}",
            "persistence true", f"persistence_location {f / 'data'}/", "autosave_on_changes true", "autosave_interval 1",
            "max_queued_messages 100000", "set_tcp_nodelay true", f"log_dest file {f / 'mosquitto.log'}", "log_type error", "log_type warning",
            "log_type notice",
            f"listener {self.port} 127.0.0.1",
            f"listener {self.tls_port} 127.0.0.1", f"cafile {self.tls['ca']}", f"certfile {self.tls['cert']}",
            f"keyfile {self.tls['key']}", ""])

    def start(self, timeout_s: float = 10.0) -> "Broker":
        self.process = subprocess.Popen([MOSQUITTO, "-c", str(self.conf)], stdout=subprocess.DEVNULL,
                                        stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError(f"mosquitto exited {self.process.returncode}: {self.log()[-800:]}")
            try:
                with socket.create_connection(("127.0.0.1", self.port), 0.2), \
                        socket.create_connection(("127.0.0.1", self.tls_port), 0.2):
                    return self
            except OSError:
                time.sleep(0.05)
        raise RuntimeError(f"mosquitto did not listen within {timeout_s} s: {self.log()[-800:]}")

    def stop(self, sig=signal.SIGTERM) -> None:
        """Stop the broker (SIGTERM: it saves its queues first; SIGKILL: as a crash)."""
        if self.process is not None and self.process.poll() is None:
            self.process.send_signal(sig)
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(5)
        self.process = None

    def restart(self) -> None:
        self.stop()
        self.start()

    def log(self) -> str:
        path = self.folder / "mosquitto.log"
        return path.read_text(errors="replace") if path.exists() else ""

    def cell_plant(self, cell: str, outbox: Path, tls: bool = True, **extra) -> dict:
        """The ``plant:`` section of a station file for ``cell`` on this broker."""
        user, password = cell_user(cell)
        mqtt = {"host": "127.0.0.1", "port": self.tls_port if tls else self.port, "topic_prefix": f"{PREFIX}/{cell}",
                "username": user, "password": password}
        if tls:
            mqtt["tls"] = {"ca": str(self.tls["ca"])}
        return {"outbox": str(outbox), "mqtt": mqtt, **extra}

    def fleet_mqtt(self, tls: bool = True) -> dict:
        mqtt = {"host": "127.0.0.1", "port": self.tls_port if tls else self.port, "username": FLEET_USER,
                "password": FLEET_PASSWORD}
        if tls:
            mqtt["tls"] = {"ca": str(self.tls["ca"])}
        return mqtt
