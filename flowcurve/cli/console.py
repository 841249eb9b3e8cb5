"""``flowcurve console``: the operator's console in the browser (``flowcurve.console``).

The server is imported only when the command runs, so ``flowcurve --help`` stays fast and
works without the ``console`` extra installed.
"""

from __future__ import annotations

import secrets
import sys
from pathlib import Path

from flowcurve.errors import FlowcurveError


def register(subparsers) -> None:
    """Add ``console`` to the subcommands."""
    p = subparsers.add_parser(
        "console",
        help="the operator's console: set up, run and watch tests in a web page",
        description=(
            "Serve a local web page to set up a test, watch it live (force-displacement and "
            "temperature plots, state, heater), stop or abort it, enter the post-test "
            "measurements and see the identified result; list the records in --out and fit a "
            "series to a material card. The test runs in this process on the rig of --config "
            "(or on the virtual rig) with the same code as 'flowcurve run'; closing the page "
            "does not stop it. Needs the 'console' extra (pip install 'flowcurve[console]')."
        ),
    )
    p.add_argument("--config", type=Path, help="rig configuration (TOML); without it the virtual rig runs in this process")
    p.add_argument("--out", type=Path, default=Path("console"), help="folder for records, results, fits and cards (default ./console)")
    p.add_argument("--host", default="127.0.0.1", help="interface to listen on (default 127.0.0.1, this computer only; any other needs a token)")
    p.add_argument("--port", type=int, default=8080, help="port (default 8080)")
    p.add_argument("--token", help="access token the page asks for (default: a random one when --host is not 127.0.0.1, where it may not be empty)")
    p.add_argument("--allow-host", action="append", default=[], metavar="NAME",
                   help="a further name or address the page may be opened by (a LAN name), besides localhost, 127.0.0.1, [::1] and --host; repeatable")
    p.add_argument("--forwarded-allow-ips", metavar="ADDRS",
                   help="the reverse proxy (addresses or networks, comma-separated) whose X-Forwarded-For names the client; "
                        "the wrong-token limit then keys on that client. Default: none, proxy headers are ignored and the limit "
                        "keys on the connection's own address")
    p.add_argument("--time-scale", type=float, default=None, metavar="X", help="virtual rig: model seconds per wall second (default 15, as 'run')")
    p.set_defaults(func=cmd_console)


def cmd_console(args) -> int:
    """``flowcurve console``: serve the operator's console until stopped; the exit status."""
    try:
        import uvicorn  # noqa: F401  (the server's)

        from flowcurve.console.request_guard import MAX_TEXT_CHARS, split_host
        from flowcurve.console.server import DEFAULT_HOST, Console, serve
    except ImportError as exc:
        raise FlowcurveError(f"the console needs the 'console' extra: pip install 'flowcurve[console]' ({exc.name} is missing)") from None
    if not 0 < args.port < 65536:
        raise FlowcurveError(f"--port must be 1-65535, got {args.port}")
    if args.time_scale is not None and not args.time_scale > 0:
        raise FlowcurveError(f"--time-scale must be a positive number, got {args.time_scale}")
    config = None
    if args.config is not None:
        from flowcurve.rig.config import load_config

        config = load_config(args.config)
    for name in args.allow_host:
        parts = split_host(f"[{name}]" if name.count(":") > 1 and not name.startswith("[") else name)  # a bare IPv6 address too
        if parts is None or parts[1] is not None:
            raise FlowcurveError(f"--allow-host: not a host name or address (without a port): {name!r}")
    proxies = forwarded_allow_ips(args.forwarded_allow_ips)
    token = args.token
    if args.host != DEFAULT_HOST:
        if token is not None and not token.strip():
            raise FlowcurveError(f"--host {args.host} needs a non-empty --token (or none: a random one is made); only --host {DEFAULT_HOST} may serve without one")
        token = token or secrets.token_urlsafe(18)
    if token is not None and len(token) > MAX_TEXT_CHARS:
        raise FlowcurveError(f"--token: at most {MAX_TEXT_CHARS} characters")
    console = Console(args.out, config=config, time_scale=args.time_scale, token=token,
                      rig_name=f"rig {args.config}" if args.config else "virtual rig",
                      host=args.host, port=args.port, allow_hosts=args.allow_host, forwarded_allow_ips=proxies)
    where = f"http://{'[' + args.host + ']' if ':' in args.host else args.host}:{args.port}/"
    print(f"flowcurve console on {where} — {console.rig_name}, records in {console.workspace.records}", file=sys.stderr)
    if token:
        print(f"access token (the page asks for it): {token}", file=sys.stderr)
    serve(console, args.host, args.port)
    return 0


def forwarded_allow_ips(value: str | None) -> str | None:
    """--forwarded-allow-ips as uvicorn takes it (``10.0.0.2,192.168.1.0/24``), or None; each an
    address or a network ("*" refused: any client could then name itself)."""
    import ipaddress

    if value is None:
        return None
    items = []
    for item in (part.strip() for part in value.split(",")):
        try:  # as uvicorn reads them: a network strictly (10.0.0.0/24), else an address
            items.append(str(ipaddress.ip_network(item, strict=False) if "/" in item else ipaddress.ip_address(item)))
        except ValueError:
            raise FlowcurveError(f"--forwarded-allow-ips: not an address or network: {item!r} (give the proxy's, e.g. 127.0.0.1 or 10.0.0.0/24)") from None
    return ",".join(items)
