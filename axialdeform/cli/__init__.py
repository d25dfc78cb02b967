"""The ``axialdeform`` command (also ``python -m axialdeform``): dispatch only.

Each sub-command is one module of this package with ``add_parser(subparsers)``
(which calls ``subparsers.add_parser(NAME, ...)`` and
``set_defaults(handler=run)``) and ``run(args) -> int | None``.  Every
argparse, print and progress bar of the package lives in ``cli/``.

User errors print one line to stderr and exit with status 2, no traceback.
"""

from __future__ import annotations

import argparse
import errno
import importlib
import os
import re
import sys

from ..core.errors import AxialDeformError
from ..core.io.safeio import quiet_numpy

__all__ = ["main", "build_parser", "COMMANDS", "PLUGINS"]

#: the built-in sub-commands, in the order ``--help`` lists them (module ``axialdeform.cli.<name>``)
COMMANDS: tuple[str, ...] = ("demo", "random", "scatter", "render", "bake", "info", "convert", "export", "fit", "learn", "view",
                             "bench", "web")

#: further modules that add sub-commands (the plugin hook): each defines
#: ``add_parser(subparsers)`` and ``run(args)`` like the built-in ones
PLUGINS: tuple[str, ...] = ()


class _Parser(argparse.ArgumentParser):
    """argparse, with a bad argument said in ONE line (and exit status 2) like every other error of
    the command line, instead of the usage block and then the error."""

    def error(self, message):
        if "COMMAND" in message:  # no command at all: what there is to ask for
            self.print_usage(sys.stderr)
        self.exit(2, f"{self.prog}: error: {one_line(message)} (see '{self.prog} --help')\n")


#: what the operating system's refusals mean for the file being written or read
_OS_HINTS = {errno.ENOSPC: "the disk is full; expected room for the output (free some space or write elsewhere)",
             errno.EDQUOT: "the disk quota is used up; expected room for the output",
             errno.EACCES: "permission denied; expected a file or folder this user may use",
             errno.EROFS: "the file system is read-only; expected a writable place for the output"}


def os_error_in_words(exc: OSError) -> str:
    """An operating system error as one sentence naming the file: ``PATH: the disk is full; ...``."""
    what = _OS_HINTS.get(exc.errno, exc.strerror or str(exc))
    return f"{exc.filename}: {what}" if getattr(exc, "filename", None) else what


def build_parser() -> argparse.ArgumentParser:
    from .. import __version__

    p = _Parser(
        prog="axialdeform",
        description="Thousands of individually different shapes from one base mesh and 16 numbers per instance.",
    )
    p.add_argument("--version", action="version", version=f"axialdeform {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in COMMANDS:
        importlib.import_module(f"{__name__}.{name}").add_parser(sub)
    for module in PLUGINS:
        importlib.import_module(module).add_parser(sub)
    return p


#: C0 and C1 control characters and DEL: escaped before they reach the terminal
_CONTROL = {c: f"\\x{c:02x}" for c in (*range(0x20), 0x7F, *range(0x80, 0xA0))}
_CONTROL.update({ord("\n"): "\\n", ord("\r"): "\\r", ord("\t"): "\\t"})


def one_line(text) -> str:
    """``text`` safe to print as one line: a newline, an escape sequence or any
    other control character (in a file name, say) is shown escaped, never
    obeyed by the terminal."""
    return str(text).translate(_CONTROL)


#: options whose value is a list of numbers (X,Y,Z; DX,DZ; R,G,B): a value that starts with a minus is
#: still their value (``--eye -2,8,12``), not an option of its own as argparse would take it
VECTOR_OPTIONS = frozenset({"--eye", "--target", "--walk", "--wind-dir", "--tint-color", "--bend", "--yaw", "--tilt"})
_NEGATIVE_LIST = re.compile(r"-(\d|\.\d)[0-9.eE+-]*(,[-+]?[0-9.eE+-]+)*")


def join_vector_values(argv) -> list:
    """``argv`` with ``--eye -2,8,12`` written ``--eye=-2,8,12`` (every option of :data:`VECTOR_OPTIONS`
    followed by a value that starts with a minus and is numbers and commas)."""
    out, i = [], 0
    argv = list(argv)
    while i < len(argv):
        a = argv[i]
        if a in VECTOR_OPTIONS and i + 1 < len(argv) and _NEGATIVE_LIST.fullmatch(str(argv[i + 1])):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(join_vector_values(sys.argv[1:] if argv is None else argv))
    import warnings

    from ..core.material import AssetWarning

    package = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

    def show(message, category, filename, lineno, file=None, line=None):
        # the library's own warnings (an asset, a mesh too small for LOD, a pass
        # that fell back): one line, no source context
        if issubclass(category, AssetWarning) or os.path.abspath(str(filename)).startswith(package + os.sep):
            print(f"axialdeform {args.command}: warning: {one_line(message)}", file=sys.stderr)
        elif issubclass(category, (DeprecationWarning, PendingDeprecationWarning, ImportWarning)):
            return  # another library's notes to its developers: not the user's business
        else:  # another library's: one line too, never its source line
            origin = os.path.basename(os.path.dirname(str(filename))) or os.path.basename(str(filename))
            print(f"axialdeform {args.command}: warning (from {one_line(origin)}): {one_line(message)}", file=sys.stderr)

    previous, warnings.showwarning = warnings.showwarning, show
    try:
        with quiet_numpy():  # floating-point trouble is checked and reported, never printed as warnings
            status = args.handler(args)
        if status:
            return int(status)
    except AxialDeformError as exc:
        print(f"axialdeform {args.command}: error: {one_line(exc)}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"axialdeform {args.command}: error: {one_line(os_error_in_words(exc))}", file=sys.stderr)
        return 2
    except MemoryError:
        print(f"axialdeform {args.command}: error: out of memory (the input asks for more than this machine has; "
              "use fewer instances or a smaller --size)", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"axialdeform {args.command}: interrupted", file=sys.stderr)
        return 130
    finally:
        warnings.showwarning = previous
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
