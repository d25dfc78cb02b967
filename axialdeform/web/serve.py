"""A small HTTP server for a folder page, that serves the page and nothing else.

``axialdeform web --serve`` runs it.  What it answers, and only that:

- it listens on the loopback address 127.0.0.1 alone;
- a request whose ``Host`` header is not the loopback name of this server (``127.0.0.1``,
  ``localhost`` or ``[::1]``, with this port or none) is refused (403): a page of another site open in
  the same browser cannot reach the server through a host name of its own (DNS rebinding);
- ``files`` given (the page's files, :func:`~axialdeform.web.files.page_files`): those paths alone;
  else any regular file of the folder that is not a dotfile and not under a dot-folder;
- a path that resolves outside the folder (``..``, a symlink out) is refused -- unless it resolves into
  one of the folders ``follow`` names, given by the caller (a test site's ``node_modules`` links) -- and
  so is a path with a NUL or backslash; a folder is never listed (``/`` is its ``index.html`` when
  that is served);
- only GET and HEAD.

Everything else is a 404 (or 403 for a foreign host) with a one-line body.
"""

from __future__ import annotations

import errno
import operator
import os
import posixpath
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from urllib.parse import unquote, urlsplit

from ..core.errors import AxialDeformError

__all__ = ["make_server"]

_TYPES = {".js": "text/javascript", ".mjs": "text/javascript", ".json": "application/json",
          ".glb": "model/gltf-binary", ".adp": "application/octet-stream", ".html": "text/html; charset=utf-8",
          ".bin": "application/octet-stream", ".wasm": "application/wasm"}
_LOOPBACK = ("127.0.0.1", "localhost", "[::1]")


def _allowed_hosts(port: int) -> frozenset:
    return frozenset([*_LOOPBACK, *(f"{h}:{port}" for h in _LOOPBACK)])


class _PageHandler(SimpleHTTPRequestHandler):
    """Serves ``self.folder``'s allowed files (see the module's docstring)."""

    extensions_map = {**SimpleHTTPRequestHandler.extensions_map, **_TYPES}
    folder: Path = Path(".")
    files: frozenset | None = None
    follow: tuple = ()

    def log_message(self, format, *args):  # quiet: the CLI prints the URL only
        pass

    def _refuse(self, code: int, why: str) -> None:
        body = (why + "\n").encode("utf-8")
        self.send_response(code)
        self.send_header("Content-Type", "text/plain; charset=utf-8")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _resolve(self) -> Path | None:
        """The file to answer, or None (then a response was sent)."""
        host = (self.headers.get("Host") or "").strip().lower()
        if host not in _allowed_hosts(self.server.server_address[1]):
            self._refuse(403, "forbidden: this server answers only http://127.0.0.1")
            return None
        raw = unquote(urlsplit(self.path).path, errors="strict")
        rel = posixpath.normpath(raw).lstrip("/")
        if rel in ("", "."):
            rel = "index.html"
        parts = rel.split("/")
        if ("\x00" in raw or "\\" in raw or raw.count("..") or any(p.startswith(".") for p in parts)
                or (self.files is not None and rel not in self.files)):
            self._refuse(404, "not found")
            return None
        root = self.folder
        path = root.joinpath(*parts)
        try:
            real = path.resolve(strict=True)
        except (OSError, RuntimeError):
            self._refuse(404, "not found")
            return None
        if not any(real.is_relative_to(r) for r in (root, *self.follow)) or not real.is_file():
            self._refuse(404, "not found")
            return None
        return real

    def send_head(self):
        try:
            real = self._resolve()
        except UnicodeDecodeError:
            self._refuse(404, "not found")
            return None
        if real is None:
            return None
        try:
            f = open(real, "rb")
        except OSError:
            self._refuse(404, "not found")
            return None
        try:
            size = os.fstat(f.fileno()).st_size
            self.send_response(200)
            self.send_header("Content-Type", self.guess_type(str(real)))
            self.send_header("Content-Length", str(size))
            self.send_header("X-Content-Type-Options", "nosniff")
            self.send_header("Cache-Control", "no-store")
            self.end_headers()
            return f
        except Exception:
            f.close()
            raise

    def list_directory(self, path):  # never a listing
        self._refuse(404, "not found")
        return None

    def do_POST(self):  # noqa: N802 (http.server's names)
        self._refuse(405, "method not allowed")

    do_PUT = do_DELETE = do_PATCH = do_OPTIONS = do_POST


def make_server(folder: str | os.PathLike, port: int = 8000, *, files=None, follow=()):
    """An HTTP server for ``folder`` on 127.0.0.1 (not started), answering only what the module's
    docstring lists.

    Parameters
    ----------
    folder : path
        The folder of a page.
    port : int
        0 .. 65535 (0: any free one).
    files : iterable of str or None
        The folder's relative paths (``/``-separated) to serve, and no others (``axialdeform web --serve``
        gives the page's own: :func:`~axialdeform.web.files.page_files`); None: every regular,
        non-hidden file inside the folder.
    follow : iterable of paths
        Folders outside ``folder`` that its symlinks may lead into (none by default: a symlink out of the
        folder is refused).

    Returns ``(server, busy)``: when ``port`` is taken the operating system picks a free one and ``busy``
    is True.  Call ``server.serve_forever()``; ``server.server_address[1]`` is the port."""
    folder = Path(folder)
    if not folder.is_dir():
        raise AxialDeformError(f"{folder}: no such folder to serve")
    handler = type("PageHandler", (_PageHandler,), {
        "folder": folder.resolve(), "files": None if files is None else frozenset(str(f) for f in files),
        "follow": tuple(Path(f).resolve() for f in follow)})
    try:
        number = operator.index(port)
    except TypeError:
        number = -1
    if not 0 <= number <= 65535:
        raise AxialDeformError(f"serve: expected a TCP port 0..65535 (0: any free one), found {port!r}")
    try:
        return ThreadingHTTPServer(("127.0.0.1", number), handler), False
    except OSError as exc:
        if exc.errno not in (errno.EADDRINUSE, errno.EACCES):
            raise AxialDeformError(f"serve: cannot listen on 127.0.0.1:{number}: {exc.strerror}") from None
    return ThreadingHTTPServer(("127.0.0.1", 0), handler), True
