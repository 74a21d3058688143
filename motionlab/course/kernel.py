"""Executing a notebook headless, with a time limit per cell and a watch for a kernel that stops answering.

:func:`execute_notebook` runs every code cell of a notebook in a fresh kernel (nbclient), as ``make course``
and the stress harness (:mod:`motionlab.course.stress`) do. Two things can keep a cell from finishing:

* **The cell is slow**: it runs past its limit (:class:`CellLimits.cell_seconds`), which the course derives
  from the chapter's budget, so a cell that should take seconds never gets twenty minutes. This raises
  nbclient's ``CellTimeoutError``.
* **The kernel stopped answering**: it is alive and idle, but the request never started (no message on
  IOPub carries the request as its parent), or the cell finished (IOPub said ``idle``) but its reply never
  came. Waiting longer cannot help: after :class:`CellLimits.answer_seconds` this raises
  :class:`KernelNotAnswering`, naming the cell and what was missing, with a short diagnosis (its CPU use over
  a second, whether it still answers on its control and on its shell channel).

In both cases the kernel is killed, not asked to shut down, and the executed part of the notebook is kept.
A kernel can also die before it ever answers (its start-up output goes to the caller's stderr);
:attr:`Execution.never_started` says so, and the course then starts the chapter again
(:func:`motionlab.course.run.execute_chapter`).

The client also polls its sockets in steps of :data:`POLL_SECONDS` rather than waiting once for a whole cell's
limit. nbclient's own client waits in one poll, and in widget cells (where it also sends on the shell socket
while it waits) its event loop sometimes misses ZeroMQ's edge-triggered wake-up: the reply then sits unread
until the poll times out (measured with :mod:`motionlab.course.stress`; README, "Reliability"). Polling in
steps turns that into a delay of at most a second (see :meth:`WatchedClient._async_poll_for_reply`).
"""

from __future__ import annotations

import asyncio
import atexit
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from queue import Empty
from typing import Any

import nbformat
from nbclient import NotebookClient
from nbclient.exceptions import CellExecutionComplete, CellTimeoutError, DeadKernelError
from nbclient.util import ensure_async
from nbformat import NotebookNode

from motionlab.validation import Checked, real

#: How often the reply channel is polled while a cell runs (seconds).
POLL_SECONDS = 1.0

#: A cell whose reply reaches the client this long after the kernel said it is idle has stalled (seconds).
STALL_SECONDS = 2.0


@dataclass(frozen=True)
class CellLimits(Checked):
    """Time limits for the cells of one notebook.

    ``cell_seconds``: the longest any one cell may run. ``answer_seconds``: how long the kernel may take
    to start a request it was sent, or to send the reply of a cell it has finished; a healthy kernel does
    either in milliseconds, so a few tens of seconds only ever trip on a kernel that stopped answering.
    """

    cell_seconds: float = real(above=0)
    answer_seconds: float = real(30.0, above=0)


class KernelNotAnswering(RuntimeError):
    """The kernel is alive but no longer answers a request: which cell, what was missing, and a diagnosis."""

    def __init__(self, cell_index: int, missing: str, waited: float, diagnosis: dict[str, Any]) -> None:
        self.cell_index = cell_index
        self.missing = missing
        self.waited = waited
        self.diagnosis = diagnosis
        super().__init__(
            f"cell {cell_index}: the kernel stopped answering ({missing} after {waited:.0f} s; "
            + ", ".join(f"{key} {value}" for key, value in diagnosis.items())
            + ")"
        )


@dataclass
class Execution:
    """What :func:`execute_notebook` did: the notebook with the outputs it got, the time, and the failure."""

    notebook: NotebookNode
    seconds: float
    error: BaseException | None = None
    #: The index of the cell that failed (None when none did, or the failure was outside a cell).
    failed_cell: int | None = None
    notes: list[str] = field(default_factory=list)
    #: Whether the kernel started and answered its first request.
    kernel_answered: bool = True

    @property
    def hung(self) -> bool:
        """Whether the kernel stopped answering."""
        return isinstance(self.error, KernelNotAnswering)

    @property
    def never_started(self) -> bool:
        """Whether the kernel died, or never answered, before the first cell."""
        return self.error is not None and not self.kernel_answered


def _process_cpu_seconds(pid: int) -> float | None:
    """User plus system CPU time of a process (Linux ``/proc``), or None where that cannot be read."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


class TimedClient(NotebookClient):
    """nbclient's own client, timed: when each request's first IOPub message and its ``idle`` status reached
    the client, and which cells the client was done with only :data:`STALL_SECONDS` or more after that
    ``idle`` (:attr:`stalls`, ``(cell index, seconds after idle, seconds in all)``): their replies came
    late."""

    def __init__(self, nb: NotebookNode, **kw: Any) -> None:
        super().__init__(nb, **kw)
        self._first_seen: dict[str, float] = {}
        self._idle_seen: dict[str, float] = {}
        self._current_cell = -1
        self.stalls: list[tuple[int, float, float]] = []
        self.kernel_answered = False  # set once the new kernel has answered its first request

    async def async_start_new_kernel_client(self) -> Any:
        try:
            client = await super().async_start_new_kernel_client()
        except Exception:
            # nbclient has cleaned the dead kernel up but left its clean-up registered for the interpreter's
            # exit, where it would fail on the manager it has since dropped
            atexit.unregister(self._cleanup_kernel)
            raise
        self.kernel_answered = True
        return client

    def process_message(self, msg: dict[str, Any], cell: NotebookNode, cell_index: int) -> Any:
        parent = msg.get("parent_header", {}).get("msg_id")
        now = time.monotonic()
        self._first_seen.setdefault(parent, now)
        if msg.get("msg_type") == "status" and msg.get("content", {}).get("execution_state") == "idle":
            self._idle_seen.setdefault(parent, now)
        return super().process_message(msg, cell, cell_index)

    async def async_execute_cell(self, cell: NotebookNode, cell_index: int, *args: Any, **kwargs: Any) -> Any:
        self._current_cell = cell_index
        idle_before = set(self._idle_seen)
        start = time.monotonic()
        result = await super().async_execute_cell(cell, cell_index, *args, **kwargs)
        now = time.monotonic()
        idle = [self._idle_seen[msg_id] for msg_id in self._idle_seen.keys() - idle_before]
        if idle and (late := now - max(idle)) >= STALL_SECONDS:
            self.stalls.append((cell_index, round(late, 1), round(now - start, 1)))
        return result


class WatchedClient(TimedClient):
    """nbclient's client with :class:`CellLimits`: polls the reply in short steps and, between them, checks
    that the kernel started the request and, once it finished the cell, that the reply arrives."""

    def __init__(self, nb: NotebookNode, limits: CellLimits, **kw: Any) -> None:
        super().__init__(nb, timeout=int(limits.cell_seconds), **kw)
        self.limits = limits

    async def _async_poll_output_msg(self, parent_msg_id: str, cell: NotebookNode, cell_index: int) -> None:
        """nbclient's IOPub loop, polled in steps of :data:`POLL_SECONDS` (see
        :meth:`_async_poll_for_reply`)."""
        assert self.kc is not None
        while True:
            try:
                msg = await ensure_async(self.kc.iopub_channel.get_msg(timeout=POLL_SECONDS))
            except Empty:
                continue
            if msg["parent_header"].get("msg_id") == parent_msg_id:
                try:
                    self.process_message(msg, cell, cell_index)
                except CellExecutionComplete:
                    return

    async def _async_poll_for_reply(
        self,
        msg_id: str,
        cell: NotebookNode,
        timeout: int | None,
        task_poll_output_msg: asyncio.Future[Any],
        task_poll_kernel_alive: asyncio.Future[Any],
    ) -> dict[str, Any]:
        """nbclient's reply loop, polled in steps of :data:`POLL_SECONDS` instead of one wait for the whole
        cell limit. Every new poll first asks the socket whether a message is waiting, so a wake-up that the
        event loop missed (ZeroMQ signals readiness by edges) costs a second, not the rest of the limit;
        between the steps the request's progress is checked (:meth:`_missing`)."""
        assert self.kc is not None
        sent = time.monotonic()
        while True:
            try:
                msg = await ensure_async(self.kc.shell_channel.get_msg(timeout=POLL_SECONDS))
            except Empty:
                now = time.monotonic()
                await self._async_check_alive()
                missing, since = self._missing(msg_id, sent, now)
                if missing is not None:
                    task_poll_kernel_alive.cancel()
                    diagnosis = await self._diagnose(msg_id)
                    self.shutdown_kernel = "immediate"
                    raise KernelNotAnswering(self._current_cell, missing, now - since, diagnosis) from None
                if timeout is not None and now - sent > timeout:
                    task_poll_kernel_alive.cancel()
                    self.shutdown_kernel = "immediate"
                    raise CellTimeoutError.error_from_timeout_and_cell(
                        f"Cell execution timed out (limit {timeout} s)", timeout, cell
                    ) from None
                continue
            if msg["parent_header"].get("msg_id") != msg_id:
                continue
            try:
                await asyncio.wait_for(task_poll_output_msg, self.iopub_timeout)
            except (TimeoutError, Empty):
                self.log.warning("Timeout waiting for IOPub output")
            task_poll_kernel_alive.cancel()
            return msg

    def _missing(self, msg_id: str, sent: float, now: float) -> tuple[str | None, float]:
        """What the kernel owes for request ``msg_id`` past :attr:`CellLimits.answer_seconds`, and since
        when."""
        answer = self.limits.answer_seconds
        if msg_id not in self._first_seen:
            return ("the request never started: no IOPub message" if now - sent > answer else None), sent
        idle = self._idle_seen.get(msg_id)
        if idle is not None and now - idle > answer:
            return "the cell finished (IOPub idle) but its reply never came", idle
        return None, sent

    async def _ask(self, channel: Any, seconds: float) -> tuple[bool, list[dict[str, Any]]]:
        """Send a ``kernel_info_request`` on ``channel``; whether it was answered within ``seconds``, and the
        other messages that came meanwhile."""
        assert self.kc is not None
        request = self.kc.session.msg("kernel_info_request")
        channel.send(request)
        deadline = time.monotonic() + seconds
        others = []
        while time.monotonic() < deadline:
            try:
                reply = await ensure_async(channel.get_msg(timeout=POLL_SECONDS))
            except Empty:
                continue
            if reply["parent_header"].get("msg_id") == request["header"]["msg_id"]:
                return True, others
            others.append(reply)
        return False, others

    async def _diagnose(self, msg_id: str) -> dict[str, Any]:
        """A short diagnosis of a kernel that stopped answering request ``msg_id``: its CPU use over one
        second, whether it still answers on its control channel, and whether a second request on the shell
        channel is answered and brings the missing reply along (a request stranded in the kernel's socket
        until the next message woke it). Each question waits up to 5 s, or the answer limit if shorter."""
        assert self.km is not None and self.kc is not None
        diagnosis: dict[str, Any] = {}
        pid = getattr(getattr(self.km, "provisioner", None), "pid", None)
        if pid is not None:
            before = _process_cpu_seconds(pid)
            await asyncio.sleep(1.0)
            after = _process_cpu_seconds(pid)
            if before is not None and after is not None:
                diagnosis["cpu_seconds_in_1s"] = round(after - before, 3)
        ask_seconds = min(5.0, self.limits.answer_seconds)  # no longer than the request was given
        diagnosis["control_answers"], _ = await self._ask(self.kc.control_channel, ask_seconds)
        diagnosis["shell_answers"], others = await self._ask(self.kc.shell_channel, ask_seconds)
        diagnosis["late_reply_came"] = any(m["parent_header"].get("msg_id") == msg_id for m in others)
        return diagnosis


def execute_notebook(
    notebook: NotebookNode,
    cwd: Path,
    limits: CellLimits,
    *,
    store_widget_state: bool = True,
    stock: bool = False,
) -> Execution:
    """Execute ``notebook`` (in place) in a fresh ``python3`` kernel started in ``cwd``.

    Never raises for what happens inside the notebook: an error, a cell over its limit, a dead kernel or one
    that stopped answering are returned as :attr:`Execution.error` with the index of the cell. With ``stock``,
    nbclient's own client executes (timed, :class:`TimedClient`; for comparison in
    :mod:`motionlab.course.stress`).
    """
    options = dict(
        kernel_name="python3",
        resources={"metadata": {"path": str(cwd)}},
        store_widget_state=store_widget_state,
    )
    client = (
        TimedClient(notebook, timeout=int(limits.cell_seconds), **options)
        if stock
        else WatchedClient(notebook, limits, **options)
    )
    start = time.perf_counter()
    error: BaseException | None = None
    try:
        client.execute()
    except (Exception, DeadKernelError) as exc:  # reported to the caller, with the cell
        error = exc
    seconds = time.perf_counter() - start
    failed = client._current_cell if error is not None and client._current_cell >= 0 else None
    return Execution(notebook, seconds, error, failed, stall_notes(client), client.kernel_answered)


def stall_notes(client: TimedClient) -> list[str]:
    """One line per stalled cell of ``client``."""
    return [
        f"cell {index}: reply {late} s after the kernel's idle status ({total} s in all, limit "
        f"{client.timeout} s)"
        for index, late, total in client.stalls
    ]


def read_notebook(path: Path) -> NotebookNode:
    """A notebook file as nbformat v4."""
    return nbformat.read(path, as_version=4)
