"""Only this server's own pages may use it: a request whose ``Host`` is not one of the server's
names is refused (DNS rebinding: a page on any site can reach ``127.0.0.1:8000`` through a name
of its own that resolves there), and so is a state-changing request (POST and the like) sent
from another site's page (CSRF), as ``Origin`` or ``Sec-Fetch-Site`` say.

Scripts (curl, Python) send no ``Origin`` and no ``Sec-Fetch-Site`` and are served; browsers
always send them on a cross-site POST.
"""
from __future__ import annotations

import ipaddress
from collections.abc import Callable, Iterable
from typing import Any
from urllib.parse import urlsplit

from fastapi.responses import JSONResponse

#: the names a loopback server answers to
LOOPBACK = ("localhost", "127.0.0.1", "::1")
#: methods that change what the server holds or does work for the caller
SAFE_METHODS = ("GET", "HEAD", "OPTIONS")
#: ``Sec-Fetch-Site`` values of requests made by this server's own pages (or typed by hand)
SAME_SITE = ("same-origin", "none")


def hosts_for(bound: str) -> frozenset[str] | None:
    """The host names a server bound to ``bound`` answers to; None: any (a server bound to
    every interface, 0.0.0.0 or ::, is reached by names it cannot know)."""
    try:
        address = ipaddress.ip_address(bound)
    except ValueError:
        return frozenset({*LOOPBACK, bound.lower()})
    if address.is_unspecified:
        return None
    return frozenset({*LOOPBACK, str(address)})


def _host_name(value: str) -> str:
    """``"127.0.0.1:8000"`` -> ``"127.0.0.1"``, ``"[::1]:8000"`` -> ``"::1"``, lower case."""
    value = value.strip().lower()
    if value.startswith("["):
        return value[1:value.find("]")] if "]" in value else value
    return value.rsplit(":", 1)[0] if value.count(":") == 1 else value


class SameSite:
    """ASGI middleware: a foreign ``Host`` gets 400, a cross-site state-changing request
    403, each as ``{"error": one line}`` naming what was sent."""

    def __init__(self, app: Any, hosts: Iterable[str] | None):
        self.app = app
        self.hosts = None if hosts is None else frozenset(hosts)

    def _refusal(self, scope: dict) -> tuple[int, str] | None:
        headers = {k.decode("latin-1").lower(): v.decode("latin-1", "replace")
                   for k, v in scope.get("headers", [])}
        host = _host_name(headers.get("host", ""))
        if self.hosts is not None and host not in self.hosts:
            return 400, (f"Host {host[:80]!r} is not this server's name (it answers to "
                         f"{', '.join(sorted(self.hosts))})")
        if scope.get("method", "GET").upper() in SAFE_METHODS:
            return None
        origin = headers.get("origin")
        if origin is not None:
            parts = urlsplit(origin)
            name = (parts.hostname or "").lower()
            allowed = self.hosts if self.hosts is not None else {host}
            if origin == "null" or name not in allowed:
                return 403, (f"a request from another site ({origin[:80]}) is refused: only "
                             "this server's own page may change anything")
            return None
        fetch_site = headers.get("sec-fetch-site")
        if fetch_site is not None and fetch_site.lower() not in SAME_SITE:
            return 403, (f"a {fetch_site[:20]} request is refused: only this server's own "
                         "page may change anything")
        return None

    async def __call__(self, scope: dict, receive: Callable, send: Callable) -> None:
        if scope["type"] == "http":
            refused = self._refusal(scope)
            if refused is not None:
                status, message = refused
                await JSONResponse({"error": message}, status_code=status)(scope, receive, send)
                return
        await self.app(scope, receive, send)
