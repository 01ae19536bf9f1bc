"""What the command line prints goes through `echo`: terminal control characters are stripped (a
failure reason or a name holding an escape sequence, a carriage return or a bell cannot retitle,
clear or overwrite the terminal), and a closed pipe (`uqflight info r.h5 | head -1`) ends the
command quietly with exit 141, as a shell's SIGPIPE would."""
from __future__ import annotations

import os
import re
import sys
from typing import NoReturn

CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f]")  # C0 but tab and newline, DEL, C1
EXIT_CLOSED_PIPE = 141  # 128 + SIGPIPE
EXIT_BAD_INPUT = 2  # a refusal: the input is wrong, nothing was done


def clean(text: str) -> str:
    """`text` without terminal control characters (tab and newline kept)."""
    return CONTROL.sub("", text)


def quoted_name(name: str) -> str:
    """A name from a file as one unambiguous entry of a listing: as it is when plain, else as repr shows it
    (quoted, control characters escaped such as \\n): a name holding a newline, a comma or a quote, or
    starting or ending with a space."""
    plain = name.isprintable() and name == name.strip() and not any(c in name for c in ",'\"")
    return name if plain and name else repr(name)


def listed(names) -> str:
    """Names from a file as one comma-separated listing, each as `quoted_name` gives it."""
    return ", ".join(quoted_name(str(name)) for name in names)


def quoted_value(value) -> str:
    """A value (read from a campaign or a file) as an error message quotes it: short, and readable for
    people who wrote YAML ("nothing", "a mapping", "a list", else its repr cut at 60 characters)."""
    if value is None:
        return "nothing"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**50:
        return "an integer of 50+ digits"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


LINE_BREAK = re.compile("[\n\u2028\u2029]")  # what `clean` keeps that starts a new line


def one_line(text: str) -> str:
    """Text from a file that is not a name (a failure reason) on one line: as it is when it holds no line
    break (echo strips its control characters), else quoted as repr shows it (a newline as \\n)."""
    text = str(text)  # a NumPy string read from a file shows as np.str_('...') in its own repr
    return repr(text) if LINE_BREAK.search(text) else text


def echo(message: object = "", err: bool = False, nl: bool = True) -> None:
    """typer.echo of `message` cleaned; a reader gone (closed pipe) exits quietly with 141."""
    import typer  # here: the quoting helpers above serve modules that never print (uqflight.analysis.surrogate)

    try:
        typer.echo(clean(str(message)), err=err, nl=nl)
    except BrokenPipeError:
        discard_output(sys.stderr if err else sys.stdout)
        raise typer.Exit(EXIT_CLOSED_PIPE) from None


def refuse(message: str) -> NoReturn:
    """A command's refusal of its input: "error: MESSAGE" on one line of standard error, and exit
    EXIT_BAD_INPUT (2). The command line's group calls it for every `uqflight.text.Refusal`
    (uqflight.cli.arguments.RefusingGroup)."""
    import typer

    echo(f"error: {message}", err=True)
    raise typer.Exit(EXIT_BAD_INPUT)


def discard_output(stream) -> None:
    """Point the stream's file descriptor at /dev/null: what it still buffers is flushed there at exit
    (not reported as another broken pipe), and what a library writes to it from C goes nowhere."""
    try:
        fd = stream.fileno()
    except (AttributeError, OSError, ValueError):  # a stream without a descriptor (tests capture output)
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)
