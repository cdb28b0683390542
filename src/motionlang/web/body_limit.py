"""A request body over a byte limit is refused (413, one line) before any of it is stored.

A pure ASGI middleware, so that it sees the body as it arrives: a declared length over the
limit is refused at once (the body read and dropped first: a reply sent before the body is
read resets the connection under the client, which then sees no reply at all), and a body
without a declared length (chunked) is counted as the multipart parser reads it and stopped
where it passes the limit, before the parser spools more of it to a temporary file.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import Any

from fastapi.responses import JSONResponse
from starlette.exceptions import HTTPException


class BodyLimit:
    """ASGI middleware: bodies over ``limit`` bytes get status 413 and
    ``{"error": message(size)}``."""

    def __init__(self, app: Any, limit: int, message: Callable[[int], str]):
        self.app, self.limit, self.message = app, limit, message

    async def __call__(self, scope: dict, receive: Callable, send: Callable) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        length = dict(scope["headers"]).get(b"content-length", b"")
        if length.isdigit() and int(length) > self.limit:
            while True:
                message = await receive()
                if message["type"] != "http.request" or not message.get("more_body"):
                    break
            reply = JSONResponse({"error": self.message(int(length))}, status_code=413)
            await reply(scope, receive, send)
            return
        seen = 0

        async def counted() -> dict:
            nonlocal seen
            message = await receive()
            if message["type"] == "http.request":
                seen += len(message.get("body", b""))
                if seen > self.limit:
                    raise HTTPException(413, self.message(seen))
            return message

        await self.app(scope, counted, send)
