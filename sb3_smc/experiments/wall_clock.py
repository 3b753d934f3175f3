"""The wall time an experiment directory has taken over all its runs, kept while each runs (``DIR/wall_time.json``).

Every ``sb3-smc experiment`` on a directory (training or ``--no-train``) adds one entry to the directory's ledger and
rewrites it every ``interval`` seconds while it runs, and once at its end: a run stopped without warning (a
machine's or working session's end, a kill) loses at most its last interval, not all its time. ``results.json``'s
``wall_time_total_s`` is the ledger's total. A directory from before the ledger starts it from the total its
``results.json`` recorded (``"before"``): its total is then a lower bound (:func:`lower_bound`), as is the total of a
directory without a ledger, since a run stopped before it wrote ``results.json`` counted nothing there. Each entry
also names the commit of the code that ran (``commit``), so that the next run can tell what trained the SMCs of a
run that stopped (:meth:`WallClock.earlier_commit`). Runs on the same directory at once (a ``--no-train`` tabulation
beside training) each write their own entry under a lock. Only a directory that holds an experiment's records gets a
ledger: a run refused before it wrote any (a wrong ``--out``, a ``--no-train`` run of nothing) leaves none.
"""

from __future__ import annotations

import fcntl
import json
import os
import threading
import time
import uuid
import warnings
from datetime import UTC, datetime
from pathlib import Path
from types import TracebackType
from typing import Any

from pixelworld_env.atomic import atomic_write
from sb3_smc.curricula.run_directory import RunFileError

__all__ = ["LEDGER", "UNKNOWN_COMMIT", "WallClock", "lower_bound"]

LEDGER = "wall_time.json"
FORMAT = "sb3-smc-wall-time"
UNKNOWN_COMMIT = "unknown"
"""The commit of a run whose code was outside a git checkout, and the key of ``results.json``'s ``commits`` for the SMC
jobs whose commit the directory's records cannot tell (those of results written before ``commits`` was recorded)."""
RECORDS = ("run.json", "results.json", "evaluations", "cnn")
"""What an experiment writes into its directory: where one of them is, the directory is the experiment's."""


def _recorded_total(directory: Path) -> float:
    """The total wall time ``directory/results.json`` recorded (0 without one, or a damaged one): where a ledger
    starts. A file that cannot be read raises its ``OSError``: its total is not 0."""
    try:
        previous = json.loads((directory / "results.json").read_text())
        return float(previous.get("wall_time_total_s", previous.get("wall_time_s", 0.0)))
    except (FileNotFoundError, ValueError, AttributeError, TypeError):
        return 0.0


def _recorded_bound(directory: Path) -> bool:
    """Whether the total ``directory/results.json`` recorded is a lower bound: unless its results say it is not (a
    total kept by a ledger); a file that cannot be read raises its ``OSError``."""
    try:
        return json.loads((directory / "results.json").read_text()).get("wall_time_lower_bound") is not False
    except (FileNotFoundError, ValueError, AttributeError):
        return True


def _read(path: Path) -> dict[str, Any] | None:
    """The ledger at ``path`` (None where there is none), checked."""
    if not path.is_file():
        return None
    try:
        ledger = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as err:
        raise RunFileError(f"{path} is not valid JSON ({err}): the experiment's wall-time ledger; restore it, or "
                           "delete it to count from the total results.json recorded") from None
    runs = ledger.get("runs") if isinstance(ledger, dict) else None
    if (not isinstance(ledger, dict) or ledger.get("format") != FORMAT or not isinstance(runs, list)
            or not isinstance(ledger.get("before"), int | float)
            or not all(isinstance(r, dict) and isinstance(r.get("seconds"), int | float) for r in runs)):
        raise RunFileError(f"{path} is not an sb3-smc wall-time ledger (format {FORMAT!r}, 'before' seconds, "
                           "'runs' with their 'seconds'); restore it, or delete it to count from the total "
                           "results.json recorded")
    return ledger


def lower_bound(directory: Path) -> bool:
    """Whether the wall time recorded for ``directory`` is only a lower bound: it has no ledger, so its total is what
    its ``results.json`` recorded from runs that ended (a run stopped at a working session's end counted nothing), or
    its ledger began from such a total (``before`` > 0, unless ``before_lower_bound`` says that total was kept by a
    ledger too), or its ledger is damaged."""
    try:
        ledger = _read(Path(directory) / LEDGER)
    except RunFileError:
        return True
    return ledger is None or (ledger["before"] > 0 and ledger.get("before_lower_bound") is not False)


class WallClock:
    """This run's entry in ``directory``'s ledger, kept up to date by a background thread while the run lasts (use
    it as a context manager); :attr:`seconds` is this run's wall time, :meth:`total` the directory's. ``commit``: the
    commit of the code that runs, kept in the entry."""

    def __init__(self, directory: Path, *, train: bool, interval: float = 60.0, commit: str | None = None) -> None:
        self.directory, self.interval = Path(directory), interval
        self.path = self.directory / LEDGER
        _read(self.path)  # a damaged ledger is reported before any work
        self.start = time.time()
        started = datetime.fromtimestamp(self.start, UTC).isoformat(timespec="seconds")
        self.entry: dict[str, Any] = {"id": uuid.uuid4().hex[:12], "started": started, "pid": os.getpid(),
                                      "train": train, "commit": commit, "seconds": 0.0, "ended": False}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._beat, name="sb3-smc-wall-clock", daemon=True)
        self._total, self._written = 0.0, False
        self._end: float | None = None

    @property
    def seconds(self) -> float:
        """This run's wall time so far (its whole time once it has ended)."""
        return (self._end or time.time()) - self.start

    def total(self) -> float:
        """The directory's wall time over all its runs as last written (this run's included; before the ledger is
        written, the recorded total and this run's time so far)."""
        return self._total if self._written else _recorded_total(self.directory) + self.seconds

    def earlier_commit(self) -> str | None:
        """The commit of the directory's last training run other than this one (its ledger's entry; ``None`` where
        there is none or it recorded none): what trained the SMCs that no ``results.json`` recorded, those of a run
        stopped at a working session's end, or of a run training beside this ``--no-train`` one."""
        try:
            ledger = _read(self.path)
        except RunFileError:
            return None
        others = [r for r in (ledger or {}).get("runs", []) if r.get("train") and r.get("id") != self.entry["id"]]
        commit = others[-1].get("commit") if others else None
        return commit if isinstance(commit, str) else None

    def _holds_records(self) -> bool:
        return any((self.directory / name).exists() for name in RECORDS)

    def __enter__(self) -> WallClock:
        self._thread.start()
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 traceback: TracebackType | None) -> None:
        self._stop.set()
        self._thread.join()
        self._end = time.time()
        self.entry.update(seconds=round(self.seconds, 3), ended=True)
        try:
            self.write(ended=True)
        except (OSError, RunFileError) as failed:
            if kind is None:  # a failed run's own error is the one to report
                raise
            warnings.warn(f"{self.path}: this run's wall time not written ({failed})", RuntimeWarning, stacklevel=2)

    def _beat(self) -> None:
        while not self._stop.wait(self.interval):
            try:
                self.write(ended=False)
            except (OSError, RunFileError) as failed:  # the run goes on; its end writes (or reports) again
                warnings.warn(f"{self.path}: wall time not written ({failed})", RuntimeWarning, stacklevel=1)

    def write(self, *, ended: bool) -> None:
        """Put this run's entry (its seconds so far) into the ledger, under the directory's lock, once the
        directory holds the experiment's records (before, nothing is written)."""
        if not self._holds_records():
            return
        with open(self.directory / f".{LEDGER}.lock", "a+") as lock:
            fcntl.flock(lock.fileno(), fcntl.LOCK_EX)
            ledger = _read(self.path) or {"format": FORMAT, "version": 1, "before": _recorded_total(self.directory),
                                          "before_lower_bound": _recorded_bound(self.directory), "runs": []}
            self.entry.update(seconds=round(self.seconds, 3), ended=ended)
            ledger["runs"] = [r for r in ledger["runs"] if r.get("id") != self.entry["id"]] + [self.entry]
            atomic_write(self.path, json.dumps(ledger, indent=2) + "\n")
            self._total = ledger["before"] + sum(r["seconds"] for r in ledger["runs"])
            self._written = True
