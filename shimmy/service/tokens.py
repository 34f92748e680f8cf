"""API tokens: who may use the service when ``SHIMMY_AUTH=token``.

A token is ``shm_`` and 32 random bytes (URL-safe base64), shown once when it is created
(``python -m shimmy tokens create --user NAME --scope read|compute|admin``) and kept only as its
SHA-256 digest, with an id (``tok_`` and 8 hex digits, for listing and revoking), the user it
belongs to, its scope and when it was created. A presented token is hashed and compared with every
kept digest in constant time (``hmac.compare_digest``, no early exit).

The store is one JSON file, private to the server's user (0600 in the 0700 cache directory, or
``SHIMMY_TOKENS_FILE``), replaced atomically under a lock, so the command line may create and revoke
tokens while the server runs: every request checks the file's identity (inode, size, mtime) and
reads it again when it changed, so a revoked token is refused from the next request on.

Standard library only: the command line's core install manages tokens without the web extra.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import hmac
import json
import os
import pathlib
import re
import secrets
import tempfile
import threading
import time
from dataclasses import asdict, dataclass
from typing import Iterator

from . import settings

#: What a token allows, each scope including the ones before it: read (GET the parameters, the
#: OpenAPI document and one's own jobs), compute (the analyses, jobs, the workbench), admin (every
#: user's jobs: GET /api/v1/jobs, reading and deleting any job).
SCOPES = ("read", "compute", "admin")
PREFIX = "shm_"
USER_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9._@+-]{0,63}")
#: A presented token longer than this, or with other characters, is refused before hashing.
TOKEN_PATTERN = re.compile(r"[A-Za-z0-9_-]{16,128}")


class TokenError(ValueError):
    """A bad user name, scope or token id given to the command line (exit status 2)."""


@dataclass(frozen=True)
class Token:
    """A kept token: its id, user, scope, creation time and the SHA-256 of the secret (never the secret)."""

    id: str
    user: str
    scope: str
    created: float
    digest: str

    def public(self) -> dict:
        """What ``tokens list`` shows: everything but the digest."""
        return {"id": self.id, "user": self.user, "scope": self.scope,
                "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(self.created))}


def digest(secret: str) -> str:
    return hashlib.sha256(secret.encode("utf-8")).hexdigest()


def _path() -> pathlib.Path:
    return settings.tokens_file()


@contextlib.contextmanager
def _locked(path: pathlib.Path) -> Iterator[None]:
    """An exclusive lock beside the store (the command line's writers, one at a time)."""
    path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
    fd = os.open(str(path) + ".lock", os.O_RDWR | os.O_CREAT, 0o600)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def _read(path: pathlib.Path) -> list[Token]:
    try:
        raw = path.read_text()
    except FileNotFoundError:
        return []
    data = json.loads(raw)
    return [Token(**t) for t in data.get("tokens", [])]


def _write(path: pathlib.Path, tokens: list[Token]) -> None:
    fd, tmp = tempfile.mkstemp(prefix=".tokens-", dir=str(path.parent))
    try:
        os.fchmod(fd, 0o600)
        with os.fdopen(fd, "w") as fh:
            json.dump({"version": 1, "tokens": [asdict(t) for t in tokens]}, fh, indent=1)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def create(user: str, scope: str) -> tuple[Token, str]:
    """A new token for ``user`` with ``scope``: (the kept record, the secret: shown once, never kept)."""
    if not isinstance(user, str) or not USER_PATTERN.fullmatch(user):
        raise TokenError(f"user={user!r} is not a user name; allowed: 1 to 64 letters, digits and . _ @ + - "
                         "(starting with a letter or digit)")
    if scope not in SCOPES:
        raise TokenError(f"scope={scope!r} is not one of {', '.join(SCOPES)}")
    secret = PREFIX + secrets.token_urlsafe(32)
    path = _path()
    with _locked(path):
        tokens = _read(path)
        ids = {t.id for t in tokens}
        token_id = next(i for i in iter(lambda: "tok_" + secrets.token_hex(4), None) if i not in ids)
        record = Token(token_id, user, scope, time.time(), digest(secret))
        _write(path, [*tokens, record])
    return record, secret


def listed() -> list[Token]:
    return _read(_path())


def revoke(token_id: str | None = None, user: str | None = None) -> list[Token]:
    """Remove the token ``token_id``, or every token of ``user``: the removed records."""
    if (token_id is None) == (user is None):
        raise TokenError("give a token id or --user NAME")
    path = _path()
    with _locked(path):
        tokens = _read(path)
        gone = [t for t in tokens if t.id == token_id or t.user == user]
        if gone:
            _write(path, [t for t in tokens if t not in gone])
    return gone


# -- the server side: a cached view of the file, re-read when it changes -------------------------

_lock = threading.Lock()
_seen: dict[str, tuple[tuple, list[Token]]] = {}


def _current() -> list[Token]:
    path = _path()
    try:
        st = path.stat()
        ident = (st.st_ino, st.st_size, st.st_mtime_ns)
    except FileNotFoundError:
        return []
    with _lock:
        cached = _seen.get(str(path))
        if cached is not None and cached[0] == ident:
            return cached[1]
    tokens = _read(path)
    with _lock:
        _seen[str(path)] = (ident, tokens)
    return tokens


def verify(secret: str) -> Token | None:
    """The kept token whose digest is that of ``secret``, or None. Every kept digest is compared (no early
    exit), each in constant time."""
    if not isinstance(secret, str) or not TOKEN_PATTERN.fullmatch(secret):
        return None
    presented = digest(secret)
    found = None
    for token in _current():
        if hmac.compare_digest(presented, token.digest) and found is None:
            found = token
    return found


def by_id(token_id: str) -> Token | None:
    """The kept token with this id (a session names its token by id), or None once it is revoked."""
    for token in _current():
        if hmac.compare_digest(token.id.encode(), token_id.encode()):
            return token
    return None


def session_key() -> bytes:
    """The key that signs workbench session cookies: 32 random bytes beside the tokens file (0600),
    created by whichever process needs it first; every web worker reads the same one."""
    path = _path().with_name("session.key")
    try:
        return path.read_bytes()
    except FileNotFoundError:
        pass
    path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".session-", dir=str(path.parent))  # 0600
    try:
        os.write(fd, secrets.token_bytes(32))
        os.close(fd)
        with contextlib.suppress(FileExistsError):  # complete before it has its name: nobody reads half a key
            os.link(tmp, path)
    finally:
        os.unlink(tmp)
    return path.read_bytes()
