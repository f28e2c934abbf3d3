"""``linkwright serve``: the browser workbench."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from linkwright.cli.shared import CliError, app


@app.command()
def serve(
    port: Annotated[
        int, typer.Option("--port", min=1, max=65535, help="TCP port to listen on.")
    ] = 8000,
    host: Annotated[
        str,
        typer.Option(
            "--host",
            help="Address to listen on. The default serves this machine only; another "
            "address (0.0.0.0: every interface) lets other machines reach the workbench, "
            "which then asks for the token printed at start.",
        ),
    ] = "127.0.0.1",
    data_dir: Annotated[
        Path | None,
        typer.Option(
            "--data-dir",
            metavar="DIR",
            help="Where the library of saved mechanisms and the atlases live (default: "
            "$LINKWRIGHT_DATA, else the user's data directory).",
        ),
    ] = None,
    no_token: Annotated[
        bool,
        typer.Option(
            "--no-token",
            help="Beyond loopback, serve without a token: anyone who can reach the address, "
            "and any web page a browser there opens, can read and change the library.",
        ),
    ] = False,
) -> None:
    """Start the browser workbench and print its address (stop it with Ctrl-C)."""
    try:
        from linkwright.server import LOOPBACK_HOSTS, create_app, default_data_dir
        from linkwright.server.runner import make_server
    except ImportError:
        from linkwright._extras import hint

        raise CliError(hint("server")) from None
    import secrets

    root = data_dir if data_dir is not None else default_data_dir()
    local = _loopback(host)
    # On loopback, only the loopback names and the address itself may reach it (no DNS
    # rebinding from a page); beyond it, any name, but only with the token.
    hosts = (*LOOPBACK_HOSTS, host.strip("[]").lower()) if local else None
    token = None if local or no_token else secrets.token_urlsafe(24)
    try:
        application = create_app(root, allowed_hosts=hosts, token=token)
    except OSError as exc:
        raise CliError(f"--data-dir: cannot use {root}: {exc.strerror or exc}") from None
    except ValueError as exc:  # a file in the way that is not a library
        raise CliError(f"--data-dir: {exc}") from None
    _check_listen(host, port)
    shown = f"[{host}]" if ":" in host else host
    if not local and no_token:
        sys.stderr.write(
            f"warning: listening on {host} without a token: anyone who can reach this machine, "
            "and any web page a browser there opens, can read and change the library\n"
        )
    address = f"http://{shown}:{port}" + (f"/?token={token}" if token else "")
    state = application.state.library.state_note()
    sys.stdout.write(
        f"linkwright workbench on {address}  (library in {root}{state}; Ctrl-C stops it)\n"
    )
    sys.stdout.flush()
    server = make_server(application, host, port)
    try:
        server.run()
    except (OSError, SystemExit):
        raise CliError(f"--port: cannot listen on {host}:{port}") from None


def _loopback(host: str) -> bool:
    """Whether ``host`` names only this machine (every address it resolves to is loopback)."""
    import ipaddress
    import socket

    try:
        infos = socket.getaddrinfo(host, None, type=socket.SOCK_STREAM)
        return all(
            ipaddress.ip_address(str(info[4][0]).split("%")[0]).is_loopback for info in infos
        )
    except (OSError, ValueError):
        return False


def _check_listen(host: str, port: int) -> None:
    """Refuse, in one line, an address the server could not listen on (uvicorn would log a
    traceback-like error and exit)."""
    import socket

    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except socket.gaierror as exc:
        raise CliError(f"--host: cannot resolve {host!r}: {exc.strerror}") from None
    family, kind, proto, _, address = infos[0]
    with socket.socket(family, kind, proto) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind(address)
        except OSError as exc:
            why = "another program is using that port" if exc.errno == 98 else exc.strerror
            raise CliError(f"--port: cannot listen on {host}:{port}: {why}") from None


# --------------------------------------------------------------------------------------------
# Pictures, animations and exports
# --------------------------------------------------------------------------------------------
