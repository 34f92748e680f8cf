"""Running the service for a team: ``serve`` (nginx in front of gunicorn, as the image runs it),
``nginx-conf`` (that proxy's configuration, for a proxy of one's own), ``tokens`` (who may use it) and
``jobs`` (draining the job queue for an upgrade). ``tokens`` and ``jobs`` act on the server's files in
``SHIMMY_CACHE_DIR`` (the tokens file, ``SHIMMY_TOKENS_FILE`` if set, and the job store), so run them as
the server's user with its environment; a running server sees a change at its next request."""

from __future__ import annotations

import json
import sys
import time

from pathlib import Path

from ..common import EXIT_BAD_INPUT, add_command


def _cmd_serve(args) -> int:
    from ...service.nginx import ProxyConfigError
    from ...service.serve import ServeError, serve
    from ...service.settings import AuthSettingError

    try:
        return serve(args.listen, args.run_dir, args.workers, args.app_dir, args.access_log)
    except (ProxyConfigError, ServeError, AuthSettingError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT


def _cmd_nginx_conf(args) -> int:
    from ...service.nginx import ProxyConfigError, render

    try:
        print(render(args.listen, args.upstream, args.run_dir, access_log=args.access_log), end="")
    except ProxyConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    return 0


def _cmd_tokens_create(args) -> int:
    from ...service.tokens import TokenError, create

    try:
        record, secret = create(args.user, args.scope)
    except TokenError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(f"created token {record.id} for user {record.user}, scope {record.scope}; it is shown once, now, "
          "and kept only hashed. Send it as: Authorization: Bearer TOKEN (or sign in to the workbench with it).")
    print(secret)
    return 0


def _cmd_tokens_list(args) -> int:
    from ...service.tokens import listed

    rows = [t.public() for t in listed()]
    if args.json:
        print(json.dumps(rows, indent=1))
        return 0
    if not rows:
        print("no tokens")
        return 0
    print(f"{'id':<13} {'user':<24} {'scope':<8} created")
    for row in rows:
        print(f"{row['id']:<13} {row['user']:<24} {row['scope']:<8} {row['created']}")
    return 0


def _cmd_tokens_revoke(args) -> int:
    from ...service.tokens import TokenError, revoke

    try:
        gone = revoke(args.id, args.user)
    except TokenError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if not gone:
        print(f"error: no token {'of user ' + args.user if args.user else args.id}", file=sys.stderr)
        return EXIT_BAD_INPUT
    for t in gone:
        print(f"revoked {t.id} (user {t.user}, scope {t.scope}); its requests and sessions are refused from now on")
    return 0


def _cmd_jobs_status(args) -> int:
    from ...service.jobs import counts, draining

    print(json.dumps({**counts(), "draining": draining()}))
    return 0


def _cmd_jobs_drain(args) -> int:
    from ...service.jobs import counts, drain, pump

    drain()
    deadline = time.time() + args.wait
    while True:
        pump()  # settles jobs whose process is gone; starts nothing while draining
        now = counts()
        if not now["running"] or time.time() >= deadline:
            break
        time.sleep(1.0)
    print(json.dumps({**now, "draining": True}))
    if now["running"]:
        print(f"{now['running']} job(s) still running after {args.wait:g} s; stopping the server now queues them "
              "again (they start from the beginning after the restart)", file=sys.stderr)
        return 1
    return 0


def _cmd_jobs_resume(args) -> int:
    from ...service.jobs import resume

    print(json.dumps({**resume(), "draining": False}))
    return 0


def add_parsers(commands) -> None:
    p0 = add_command(commands, "serve", "run the service for a team: nginx on --listen holding slow clients, in front "
                     "of gunicorn (app:server) on a Unix socket only it reaches; SIGTERM stops both", _cmd_serve)
    p0.add_argument("--listen", default="127.0.0.1:8050", help="where nginx listens: HOST:PORT or PORT (beyond "
                    "loopback, authentication is on by default)")
    p0.add_argument("--workers", type=int, default=2, help="gunicorn's web workers")
    p0.add_argument("--run-dir", type=Path, default=None, help="private folder (0700) for gunicorn's socket and "
                    "nginx's configuration, pid and temporary files (default: shimmy-serve-UID in the temporary "
                    "directory)")
    p0.add_argument("--app-dir", type=Path, default=None, help="folder with app.py and gunicorn.conf.py (default: "
                    "the current one)")
    p0.add_argument("--access-log", default="-", help="nginx's access log: - (serve's standard output), a file, "
                    "or off")
    c0 = add_command(commands, "nginx-conf", "print the nginx configuration that serve runs (its limits from the "
                     "SHIMMY_* settings), for a proxy of one's own", _cmd_nginx_conf)
    c0.add_argument("--listen", default="127.0.0.1:8050", help="where nginx listens: HOST:PORT or PORT")
    c0.add_argument("--upstream", default="unix:/tmp/shimmy-serve/gunicorn.sock",
                    help="gunicorn's address: unix:/PATH or HOST:PORT")
    c0.add_argument("--run-dir", default="/tmp/shimmy-serve", help="folder for nginx's pid and temporary files")
    c0.add_argument("--access-log", default="/dev/stdout", help="nginx's access log: a file, or off")

    p = add_command(commands, "tokens", "create, list and revoke the API tokens of the service (SHIMMY_AUTH=token)",
                    lambda args: p.print_help() or EXIT_BAD_INPUT)
    sub = p.add_subparsers(dest="tokens_command", metavar="ACTION")
    c = add_command(sub, "create", "create a token for a user and print it (its last line), once", _cmd_tokens_create)
    c.add_argument("--user", required=True, help="whose token it is (1 to 64 letters, digits and . _ @ + -)")
    c.add_argument("--scope", required=True, choices=["read", "compute", "admin"],
                   help="read: GET parameters and one's jobs; compute: also the analyses, jobs and the workbench; "
                        "admin: also every user's jobs")
    c = add_command(sub, "list", "list the tokens: id, user, scope, created (never the token)", _cmd_tokens_list)
    c.add_argument("--json", action="store_true", help="write JSON to stdout")
    c = add_command(sub, "revoke", "revoke a token by its id, or every token of a user", _cmd_tokens_revoke)
    c.add_argument("id", nargs="?", help="the token's id (tok_...), as tokens list shows it")
    c.add_argument("--user", help="revoke every token of this user instead")

    p2 = add_command(commands, "jobs", "drain the service's job queue for an upgrade, resume it, or show it",
                     lambda args: p2.print_help() or EXIT_BAD_INPUT)
    sub = p2.add_subparsers(dest="jobs_command", metavar="ACTION")
    add_command(sub, "status", "jobs queued and running, and whether the queue is draining", _cmd_jobs_status)
    c = add_command(sub, "drain", "start no more jobs (submissions still queue) and wait for the running ones",
                    _cmd_jobs_drain)
    c.add_argument("--wait", type=float, default=600.0, help="seconds to wait for the running jobs (exit 1 if some "
                   "still run)")
    add_command(sub, "resume", "start queued jobs again (a server start resumes too)", _cmd_jobs_resume)
