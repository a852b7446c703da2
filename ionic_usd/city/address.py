"""``--scheduler`` addresses, checked before any work (issue 31): a Dask scheduler this process
can reach over the network, ``SCHEME://HOST:PORT``.

Accepted schemes are the network ones of ``distributed`` (``tcp``, ``tls``, ``ws``, ``wss``);
``inproc://`` names a scheduler inside this very process, which a city build never has, and
``http://`` is a dashboard, not a scheduler. The host must be a valid IPv4/IPv6 address or a
host name that resolves; the port an integer in [1, 65535]; and something must accept a TCP
connection there (checked before any work, even when every temple is already built).
"""

from __future__ import annotations

import ipaddress
import re
import socket
import threading

from ionic_usd.errors import ParameterError

__all__ = ["SCHEMES", "check_scheduler_address", "resolve_scheduler_host"]

SCHEMES = ("tcp", "tls", "ws", "wss")
_HOSTNAME = re.compile(
    r"^(?=.{1,253}$)([A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?)(\.[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?)*\.?$"
)
RESOLVE_TIMEOUT = 5.0  # s


def _refuse(address: object, why: str) -> ParameterError:
    return ParameterError("--scheduler", address, f"SCHEME://HOST:PORT with {why}")


def check_scheduler_address(address: object) -> tuple[str, str, int]:
    """``(scheme, host, port)`` of a well-formed address; else :class:`ParameterError`."""
    if not isinstance(address, str) or "://" not in address:
        raise _refuse(address, f"SCHEME one of {', '.join(SCHEMES)}")
    scheme, _, rest = address.partition("://")
    if scheme not in SCHEMES:
        raise _refuse(address, f"SCHEME one of {', '.join(SCHEMES)} (not {scheme!r})")
    if rest.startswith("["):  # [IPv6]:port
        host, sep, port_text = rest[1:].partition("]:")
        if not sep:
            raise _refuse(address, "a port after the IPv6 address ([ADDR]:PORT)")
    else:
        host, sep, port_text = rest.rpartition(":")
        if not sep:
            raise _refuse(address, "a PORT")
    if not host:
        raise _refuse(address, "a HOST")
    if not port_text.isdigit() or not 1 <= int(port_text) <= 65535:
        raise _refuse(address, f"PORT an integer in [1, 65535] (not {port_text!r})")
    if re.fullmatch(r"[0-9.]+", host) or ":" in host:
        try:
            ipaddress.ip_address(host)
        except ValueError:
            raise _refuse(address, f"HOST a valid IP address (not {host!r})") from None
    elif not _HOSTNAME.match(host):
        raise _refuse(address, f"HOST a valid host name (not {host!r})")
    return scheme, host, int(port_text)


def resolve_scheduler_host(address: str, timeout: float = RESOLVE_TIMEOUT) -> None:
    """Refuse an address whose host name does not resolve, or where nothing accepts a TCP
    connection (each within ``timeout`` seconds)."""
    _scheme, host, port = check_scheduler_address(address)
    result: list[BaseException | None] = []

    def look_up() -> None:
        try:
            socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
            result.append(None)
        except (OSError, UnicodeError) as exc:
            result.append(exc)

    t = threading.Thread(target=look_up, daemon=True)
    t.start()
    t.join(timeout)
    if not result:
        raise ParameterError(
            "--scheduler", address, f"a host that resolves (no answer in {timeout:g} s)"
        )
    if result[0] is not None:
        raise ParameterError("--scheduler", address, f"a host that resolves ({host}: {result[0]})")
    try:  # something listens there (a scheduler's handshake is distributed's to check)
        socket.create_connection((host, port), timeout=timeout).close()
    except OSError as exc:
        raise ParameterError(
            "--scheduler",
            address,
            f"a scheduler that accepts connections ({host}:{port}: {exc.strerror or exc})",
        ) from None
