"""What the console accepts from the network, checked before anything acts on it.

* :class:`HostAllowlist` — the names a request may be addressed to (``Host``) and come from
  (``Origin``): the loopback names with the console's port, the ``--host`` value and the
  ``--allow-host`` names. A web page elsewhere that resolves its own name to 127.0.0.1 (DNS
  rebinding) sends its own name as Host and is refused.
* :func:`read_json_object` — a body of at most :data:`MAX_BODY_BYTES`, a JSON object nested at
  most :data:`MAX_JSON_DEPTH` deep, without NaN or Infinity.
* :func:`check_fields` — each endpoint's fields by type: numbers are numbers or text (never
  true/false), text is at most :data:`MAX_TEXT_CHARS` printable characters, unknown fields refused.
* :class:`FailedLogins` — at most :data:`LOGIN_FAILURES` wrong tokens per client in
  :data:`LOGIN_WINDOW_S`; then 429 until the oldest failure is that old.

A refusal is a :class:`Refused` (status, one-line message) or a ``FormError`` (a message per
field); the server answers it as a 4xx before any test, file or rig state is touched.
"""

from __future__ import annotations

import json
import math
import threading
import time
from collections import deque
from typing import Callable

from flowcurve.errors import FlowcurveError

MAX_BODY_BYTES = 1 << 20  # 1 MiB: a set-up form is well under 1 kB
MAX_JSON_DEPTH = 32  # containers inside containers; the page sends depth 1 (fit: 2)
MAX_TEXT_CHARS = 200  # a material, operator, specimen id, record name or token
MAX_LIST_ITEMS = 1000  # records selected for one fit
LOGIN_FAILURES = 5  # wrong tokens per client ...
LOGIN_WINDOW_S = 60.0  # ... in this many seconds, then 429
LOOPBACK_NAMES = ("127.0.0.1", "localhost", "::1")


class Refused(FlowcurveError):
    """A request the console will not act on: ``status`` (4xx) and a one-line reason."""

    def __init__(self, message: str, status: int = 400):
        super().__init__(message)
        self.status = status


# -- Host and Origin -------------------------------------------------------------------------------
def split_host(value: str) -> tuple[str, int | None] | None:
    """``name[:port]`` or ``[v6]:port`` → (lower-case name, port or None); None if malformed."""
    value = value.strip().lower()
    if value.startswith("["):
        name, sep, rest = value[1:].partition("]")
        if not sep or (rest and not rest.startswith(":")):
            return None
        port_text = rest[1:] if rest else None
    elif value.count(":") == 1:
        name, port_text = value.split(":")
    else:
        name, port_text = value, None
    if not name or any(c in name for c in "/\\@ \t") or (":" in name and not value.startswith("[")):
        return None
    if port_text is None:
        return name, None
    if not (port_text.isascii() and port_text.isdigit()) or not 0 < int(port_text) < 65536:  # "²" is a digit to isdigit
        return None
    return name, int(port_text)


def host_name(value: str) -> str:
    """A name for the allowlist as given on the command line (``[::1]`` → ``::1``), lower-case."""
    value = value.strip().lower()
    return value[1:-1] if value.startswith("[") and value.endswith("]") else value


class HostAllowlist:
    """The names this console answers to, on its port (None: any port, for an embedded console)."""

    def __init__(self, names, port: int | None = None):
        self.names = frozenset(host_name(n) for n in (*LOOPBACK_NAMES, *names) if n and n.strip())
        self.port = port

    def _allows(self, name: str, port: int | None, default_port: int) -> bool:
        if name not in self.names:
            return False
        return self.port is None or (port if port is not None else default_port) == self.port

    def allows_host(self, header: str | None) -> bool:
        """The Host header names this console (HTTP/1.1 always sends one)."""
        parts = split_host(header) if header else None
        return parts is not None and self._allows(*parts, default_port=80)

    def allows_origin(self, origin: str) -> bool:
        """An Origin header (``http://name:port``) is this console's own page."""
        scheme, sep, rest = origin.strip().lower().partition("://")
        if not sep or scheme not in ("http", "https") or "/" in rest:
            return False
        parts = split_host(rest)
        return parts is not None and self._allows(*parts, default_port=80 if scheme == "http" else 443)


# -- the body ---------------------------------------------------------------------------------------
def _no_constant(name: str):
    raise ValueError(f"{name} is not a JSON number")


def json_depth(value, limit: int = MAX_JSON_DEPTH) -> int:
    """How deep containers nest in a decoded JSON value (a scalar 0, ``{}`` 1); stops past ``limit``."""
    deepest = 0
    stack = [(value, 1)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, (dict, list)):
            deepest = max(deepest, depth)
            if deepest > limit:
                return deepest
            stack.extend((child, depth + 1) for child in (item.values() if isinstance(item, dict) else item))
    return deepest


def read_json_object(body: bytes) -> dict:
    """The request's JSON object (an empty body is ``{}``), or :class:`Refused` 400/413."""
    if len(body) > MAX_BODY_BYTES:
        raise Refused(f"the request is larger than {MAX_BODY_BYTES} bytes", 413)
    if not body.strip():
        return {}
    try:
        data = json.loads(body, parse_constant=_no_constant)
    except RecursionError:
        raise Refused(f"the request's JSON nests deeper than {MAX_JSON_DEPTH} levels") from None
    except (ValueError, UnicodeDecodeError):
        raise Refused("the request is not valid JSON") from None
    if not isinstance(data, dict):
        raise Refused("the request must be a JSON object")
    if json_depth(data) > MAX_JSON_DEPTH:
        raise Refused(f"the request's JSON nests deeper than {MAX_JSON_DEPTH} levels")
    return data


# -- typed fields -----------------------------------------------------------------------------------
NUMBER, TEXT, NAMES = "number", "text", "names"  # a field's type


def _text_problem(value: str) -> str | None:
    if len(value) > MAX_TEXT_CHARS:
        return f"at most {MAX_TEXT_CHARS} characters, got {len(value)}"
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        return "not valid text (a lone surrogate)"
    if any(not c.isprintable() for c in value):
        return "control characters are not allowed"
    return None


def _field_problem(kind: str, value) -> str | None:
    if value is None:
        return None
    if kind == NAMES:
        if not isinstance(value, list):
            return "give a list of names"
        if len(value) > MAX_LIST_ITEMS:
            return f"at most {MAX_LIST_ITEMS} names"
        for item in value:
            problem = "not a name" if not isinstance(item, str) else _text_problem(item)
            if problem:
                return f"{problem}: {str(item)[:40]!r}"
        return None
    if isinstance(value, str):
        return _text_problem(value)
    if kind == NUMBER and isinstance(value, (int, float)) and not isinstance(value, bool):
        try:
            finite = math.isfinite(float(value))
        except OverflowError:
            finite = False
        return None if finite else "not a finite number"
    wanted = "a number" if kind == NUMBER else "text"
    return f"not {wanted}: {json.dumps(value)[:40]}"


def check_fields(data: dict, schema: dict[str, str]) -> None:
    """Every field of ``data`` is known to ``schema`` (field → NUMBER, TEXT or NAMES) and of its
    type; a ``FormError`` names each one that is not."""
    from flowcurve.console.setup_form import FormError

    errors: dict[str, str] = {}
    for key, value in data.items():
        if key not in schema:
            errors[key[:40] if _text_problem(key) is None else "form"] = f"unknown field: {key[:40]!r}"
            continue
        problem = _field_problem(schema[key], value)
        if problem:
            errors[key] = problem
    if errors:
        raise FormError(errors)


# -- failed logins ----------------------------------------------------------------------------------
class FailedLogins:
    """Wrong tokens per client: ``blocked(client)`` once ``limit`` fell within ``window_s``."""

    def __init__(self, limit: int = LOGIN_FAILURES, window_s: float = LOGIN_WINDOW_S, clock: Callable[[], float] = time.monotonic):
        self.limit, self.window_s, self.clock = limit, window_s, clock
        self._failures: dict[str, deque] = {}
        self._lock = threading.Lock()

    def _recent(self, client: str) -> deque:
        times = self._failures.setdefault(client, deque())
        while times and self.clock() - times[0] >= self.window_s:
            times.popleft()
        if not times:
            del self._failures[client]  # forget clients that went quiet (the table stays small)
        return times

    def retry_after_s(self, client: str) -> float:
        """Seconds until ``client`` may try again (0: it may now)."""
        with self._lock:
            times = self._recent(client)
            if len(times) < self.limit:
                return 0.0
            return max(0.0, times[0] + self.window_s - self.clock())

    def failed(self, client: str) -> None:
        """Count a failed login from ``client``."""
        with self._lock:
            self._recent(client)
            self._failures.setdefault(client, deque()).append(self.clock())

    def succeeded(self, client: str) -> None:
        """Forget ``client``'s failed logins."""
        with self._lock:
            self._failures.pop(client, None)
