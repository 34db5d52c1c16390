"""What a plugin adds to the ``gearopt`` command: subcommands and benchmarks.

A plugin contributes a subcommand (``gearopt chain ...``) by returning a :class:`BaseCommand`
from its ``gearopt_commands`` hook, and a benchmark of ``gearopt bench`` by returning a
:class:`Benchmark` from its ``gearopt_benchmarks`` hook (:mod:`gearopt.hookspecs`); the core's
own benchmarks are :class:`Benchmark` objects too (``gearopt.bench.CORE_BENCHMARKS``), and
nothing in the core names a plugin's command or benchmark.
:func:`text_table` prints the plain-text tables the core's commands print, and
:func:`time_call_ms` times a kernel as the core's benchmarks do.
"""

from __future__ import annotations

import abc
import argparse
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from gearopt.errors import PluginError

__all__ = ["BaseCommand", "Benchmark", "CallTime", "text_table", "time_call_ms"]


class BaseCommand(abc.ABC):
    """A subcommand of ``gearopt`` that a plugin provides.

    ``gearopt`` collects every plugin's commands when it builds its argument parser, adds a
    subparser called ``name`` with ``help`` as its one-line help, lets :meth:`add_arguments`
    fill it, and calls :meth:`run` with the parsed arguments when the command is given.
    Errors are reported as the core's are: a :class:`~gearopt.errors.GearoptError` raised by
    ``run`` (or by anything it calls) is printed as one line on standard error,
    ``gearopt: error: <type>: <parameter> = <value>: <rule>``, with exit status 2; anything else
    is a bug and shows its traceback. ``name`` is unique among the core's commands and every
    plugin's (a duplicate is a :class:`~gearopt.errors.PluginError` naming both).

    The hook is called each time ``gearopt`` builds its parser, before any command runs: build
    instances cheaply and leave the work to :meth:`run`.
    """

    name: ClassVar[str]
    help: ClassVar[str] = ""

    @property
    def description(self) -> str:
        """What ``gearopt plugins`` prints beside the command: its help."""
        return self.help

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        """Add the command's arguments and options to its own ``parser`` (argparse).

        The default adds none. Use ``--json`` for machine-readable output, as the core does.
        """
        return None

    @abc.abstractmethod
    def run(self, args: argparse.Namespace) -> int:
        """Run the command with its parsed ``args``; return the exit status (0: success).

        Print results on standard output; raise a :class:`~gearopt.errors.GearoptError`
        subclass naming the parameter, the value and the rule for bad input.
        """

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r}>"


@dataclass(frozen=True, kw_only=True)
class Benchmark:
    """One benchmark of ``gearopt bench``.

    Attributes
    ----------
    name
        The benchmark's name, which is also its key in ``gearopt bench --json``; by convention
        it ends with its unit (``"change_gears_ms"``).
    function
        A module-level function ``() -> (milliseconds, info)``: it times one run of its kernel
        after any warm-up it needs (:func:`time_call_ms`) and returns the facts to print beside
        the time (grid size, set size) as a JSON-ready dict whose keys do not collide with
        other benchmarks' (prefix them with the benchmark's subject). ``gearopt bench`` runs
        it in fresh processes by its module and qualified name, so it must be importable.
    description
        One line for ``gearopt plugins``.
    """

    name: str
    function: Callable[[], tuple[float, dict[str, Any]]]
    description: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise PluginError("benchmark name", self.name, "must be a non-empty string")
        qualname = getattr(self.function, "__qualname__", "")
        if not callable(self.function) or not qualname or "<" in qualname:
            raise PluginError(
                f"benchmark {self.name!r} function",
                self.function,
                "must be a module-level function (it is imported by name in a fresh process)",
            )

    @property
    def target(self) -> str:
        """``"module:qualified.name"`` of :attr:`function`, as a fresh process imports it."""
        return f"{self.function.__module__}:{self.function.__qualname__}"


class CallTime(float):
    """A call's wall time in milliseconds (the float itself), with the process's CPU time of
    the same calls beside it as :attr:`cpu_ms`: on a shared machine the wall time takes in
    other processes' load, the CPU time does not."""

    cpu_ms: float

    def __new__(cls, wall_ms: float, *, cpu_ms: float) -> CallTime:
        time_ = super().__new__(cls, wall_ms)
        time_.cpu_ms = float(cpu_ms)
        return time_


def time_call_ms(func: Callable[[], object], *, number: int = 1) -> CallTime:
    """Wall time of ``number`` calls of ``func`` divided by ``number``, in milliseconds, with
    the process's CPU time per call beside it (:class:`CallTime`)."""
    start, start_cpu = time.perf_counter(), time.process_time()
    for _ in range(number):
        func()
    cpu_ms = (time.process_time() - start_cpu) * 1e3 / number
    return CallTime((time.perf_counter() - start) * 1e3 / number, cpu_ms=cpu_ms)


def _is_number(cell: str) -> bool:
    try:
        float(cell.split(",")[0])
    except ValueError:
        return False
    return True


def text_table(rows: list[tuple[str, ...]], header: tuple[str, ...]) -> str:
    """Plain-text table: first column and text left-aligned, numbers right-aligned."""
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    lines = ["  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True)).rstrip()]
    lines.append("  ".join("-" * w for w in widths))
    for row in rows:
        cells = [row[0].ljust(widths[0])] + [
            c.rjust(w) if _is_number(c) else c.ljust(w)
            for c, w in zip(row[1:], widths[1:], strict=True)
        ]
        lines.append("  ".join(cells).rstrip())
    return "\n".join(lines)
