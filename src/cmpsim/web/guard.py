"""The token of ``cmpsim serve --token``: an ASGI middleware that lets through only requests
that carry it (as a bearer token, a cookie, or once in the page's address)."""

from __future__ import annotations

import hmac
import json
from http.cookies import SimpleCookie
from urllib.parse import parse_qs, quote, unquote

__all__ = ["TokenGuard", "TOKEN_COOKIE"]

#: Cookie that carries the token after the page was opened with ``?token=...``.
TOKEN_COOKIE = "cmpsim_token"


class TokenGuard:
    """ASGI middleware: every request needs the token, as ``Authorization: Bearer TOKEN``, the
    cookie :data:`TOKEN_COOKIE`, or ``?token=TOKEN`` (which also sets the cookie, so the page
    opened from that link can call the API)."""

    def __init__(self, app, token: str):
        self.app = app
        self.token = token.encode()

    def _match(self, candidate: str | None) -> bool:
        return candidate is not None and hmac.compare_digest(candidate.encode(), self.token)

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope.get("headers", [])}
        auth = headers.get("authorization", "")
        bearer = auth[7:].strip() if auth[:7].lower() == "bearer " else None
        cookie = None
        if "cookie" in headers:
            try:
                jar = SimpleCookie(headers["cookie"])
                if TOKEN_COOKIE in jar:
                    cookie = unquote(jar[TOKEN_COOKIE].value)
            except Exception:  # a malformed Cookie header is no token
                cookie = None
        query = parse_qs(scope.get("query_string", b"").decode("latin-1")).get("token", [None])[0]
        if self._match(bearer) or self._match(cookie):
            await self.app(scope, receive, send)
            return
        if self._match(query):
            value = f"{TOKEN_COOKIE}={quote(self.token.decode(), safe='')}; Path=/; HttpOnly; SameSite=Strict"

            async def send_with_cookie(message):
                if message["type"] == "http.response.start":
                    message = dict(message, headers=list(message.get("headers", [])) + [(b"set-cookie", value.encode("latin-1"))])
                await send(message)

            await self.app(scope, receive, send_with_cookie)
            return
        body = json.dumps(
            {
                "detail": "this server needs its token: send 'Authorization: Bearer TOKEN', or open the page once as /?token=TOKEN",
                "parameter": None,
            }
        ).encode()
        await send(
            {
                "type": "http.response.start",
                "status": 401,
                "headers": [(b"content-type", b"application/json"), (b"www-authenticate", b"Bearer"), (b"content-length", str(len(body)).encode())],
            }
        )
        await send({"type": "http.response.body", "body": body})
