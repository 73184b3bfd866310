"""A training run's folder: each cycle's checkpoint written as one unit.

Layout::

    RUN/checkpoint               the pointer: the name of the checkpoint in force
    RUN/checkpoint-000003/       robot.zip, human.zip, log.json of one cycle, and (until it
                                 is published) the TensorBoard events of that cycle
    RUN/log.json, robot.zip, human.zip
                                 hard links to the files of the checkpoint in force
    RUN/tb/robot_0, RUN/tb/human_0
                                 TensorBoard events of the committed cycles, one file each
    RUN/rewards.png              training rewards (Figure 11), written when training ends

Committing a checkpoint: everything is written into a new ``checkpoint-NNNNNN`` folder, then
the pointer file is replaced atomically (the commit point), then the checkpoint is
*published*: its TensorBoard events move into ``tb/``, the top-level links are renewed and
older checkpoint folders are removed. Publishing is idempotent and is redone when a run is
resumed, and a checkpoint folder newer than the pointer (a cycle killed before its commit)
is removed with its TensorBoard events. So a kill at any point leaves the previous
checkpoint or the new one in force, never models newer than the log, and TensorBoard holds
each step once.

A folder written before checkpoints existed (no pointer, ``log.json`` and the models at the
top level) is read as one checkpoint.

Every change to the folder goes through the module-level functions :func:`write_bytes`,
:func:`write_text`, :func:`_replace`, :func:`_link` and :func:`_remove_tree`, so that a test
can inject a kill at any of them.
"""

from __future__ import annotations

import io
import json
import os
import re
import shutil
from pathlib import Path

from asp.atomic import write_bytes, write_text

POINTER = "checkpoint"
LOG = "log.json"
TB = "tb"
REWARDS_PNG = "rewards.png"
MODELS = ("robot.zip", "human.zip")
LOG_FORMAT = "asmplan-arl-run"
CYCLE_KEYS = frozenset(
    ("cycle", "robot_mean_reward", "human_mean_reward", "wcpl", "timesteps", "policy_hash")
)
"""Keys of a cycle record that resuming reads."""
_CHECKPOINT = re.compile(r"checkpoint-(\d{6})")


def _replace(src: Path, dst: Path) -> None:
    os.replace(src, dst)


def _link(src: Path, dst: Path) -> None:
    """Make ``dst`` the same file as ``src`` (a hard link, else a copy), atomically."""
    if dst.exists() and os.path.samefile(src, dst):
        return  # renaming a link onto the same file would leave the link behind
    tmp = dst.with_name(f".{dst.name}.link.tmp")
    tmp.unlink(missing_ok=True)
    try:
        os.link(src, tmp)
    except OSError:  # no hard links on this file system
        shutil.copyfile(src, tmp)
    os.replace(tmp, dst)


def _remove_tree(path: Path) -> None:
    if path.is_dir():
        shutil.rmtree(path)
    else:
        path.unlink(missing_ok=True)


def refuse_existing_run(path: str | os.PathLike[str] | None, *, force: bool) -> None:
    """Refuse to start a fresh run in a folder that holds a training run (its log, models
    or checkpoint pointer) unless ``force``: training over it would delete it.

    Raises
    ------
    ValueError
        One line naming the folder and the two ways on (``--resume``, ``--force``).
    """
    if path is None or force:
        return
    folder = Path(path)
    held = [n for n in (LOG, POINTER, *MODELS) if (folder / n).exists()]
    if held:
        raise ValueError(
            f"{folder}: holds a training run ({', '.join(held)}); --resume continues it, "
            "--force replaces it"
        )


class RunFolder:
    """The run folder at ``path`` (see the module docstring for its layout)."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)

    # ------------------------------------------------------------------------ reading

    @property
    def pointer(self) -> Path:
        return self.path / POINTER

    def current_index(self) -> int:
        """Index of the checkpoint in force (0: none, or a folder of the earlier layout)."""
        if not self.pointer.is_file():
            return 0
        name = self.pointer.read_text(encoding="utf-8").strip()
        match = _CHECKPOINT.fullmatch(name)
        if match is None or not (self.path / name).is_dir():
            raise ValueError(f"{self.pointer}: does not name a checkpoint folder of this run")
        return int(match.group(1))

    def current(self) -> Path:
        """The folder holding the models and log in force."""
        index = self.current_index()
        return self.path if index == 0 else self._checkpoint(index)

    def model_path(self, agent: str) -> Path:
        """The saved model of ``agent`` (``"robot"`` or ``"human"``) in force."""
        return self.current() / f"{agent}.zip"

    def log_path(self) -> Path:
        """The ``log.json`` in force."""
        return self.current() / LOG

    def read_log(self) -> dict:
        """The log in force, checked (``ValueError`` naming the file if absent or malformed)."""
        if not self.path.is_dir():
            raise ValueError(f"{self.path}: not a training run folder")
        path = self.log_path()
        if not path.is_file():
            raise ValueError(f"{self.path}: no {LOG} (not a training run folder)")
        try:
            log = json.loads(path.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError, RecursionError) as exc:
            raise ValueError(f"{path}: not valid JSON ({str(exc).splitlines()[0]})") from None
        if not isinstance(log, dict) or log.get("format") != LOG_FORMAT:
            raise ValueError(f"{path}: expected an {LOG_FORMAT} log")
        problem = _log_problem(log)
        if problem:
            raise ValueError(f"{path}: malformed run log ({problem})")
        return log

    # ------------------------------------------------------------------------ writing

    def start_fresh(self) -> None:
        """Remove what an earlier run left here (its log first, so nothing half-old resumes)."""
        for name in (POINTER, LOG, *MODELS, REWARDS_PNG, TB):
            if (self.path / name).exists():
                _remove_tree(self.path / name)
        for folder in self._checkpoints():
            _remove_tree(folder)

    def recover(self) -> None:
        """Finish publishing the checkpoint in force; drop checkpoints never committed and
        the temporary files of writes a kill interrupted."""
        for tmp in self.path.glob(".*.tmp"):
            _remove_tree(tmp)
        if self.current_index() > 0:
            self._publish()

    def discard_uncommitted(self) -> None:
        """Remove what the cycle being trained wrote (after an error: a full disk, ...)."""
        staged = self._checkpoint(self.current_index() + 1)
        if staged.exists():
            _remove_tree(staged)

    def staging_tb(self, agent: str) -> Path:
        """Where the cycle being trained writes ``agent``'s TensorBoard events."""
        return self._checkpoint(self.current_index() + 1) / TB / f"{agent}_0"

    def commit(self, log: dict, models: dict) -> None:
        """Write ``log`` and ``models`` (``{"robot": model, ...}``) as the next checkpoint."""
        folder = self._checkpoint(self.current_index() + 1)
        for agent, model in models.items():
            buffer = io.BytesIO()
            model.save(buffer)
            write_bytes(folder / f"{agent}.zip", buffer.getvalue())
        write_text(folder / LOG, json.dumps(log, indent=1) + "\n")
        write_text(self.pointer, folder.name + "\n")
        self._publish()

    def write_rewards_png(self, data: bytes) -> Path:
        return write_bytes(self.path / REWARDS_PNG, data)

    # ------------------------------------------------------------------------ internals

    def _checkpoint(self, index: int) -> Path:
        return self.path / f"checkpoint-{index:06d}"

    def _checkpoints(self) -> list[Path]:
        if not self.path.is_dir():
            return []
        return sorted(p for p in self.path.iterdir() if _CHECKPOINT.fullmatch(p.name))

    def _publish(self) -> None:
        index = self.current_index()
        folder = self._checkpoint(index)
        staged = folder / TB
        if staged.is_dir():
            for run in sorted(p for p in staged.iterdir() if p.is_dir()):
                target = self.path / TB / run.name
                target.mkdir(parents=True, exist_ok=True)
                for n, events in enumerate(sorted(run.iterdir())):
                    # Named by checkpoint, so TensorBoard reads the files in training order.
                    _replace(events, target / f"events.out.tfevents.{index:06d}.{n}")
            _remove_tree(staged)
        for name in (*MODELS, LOG):
            if (folder / name).is_file():
                _link(folder / name, self.path / name)
        for other in self._checkpoints():
            if other != folder:
                _remove_tree(other)


def _log_problem(log: dict) -> str:
    """What is missing or of the wrong type in a run log ("" if nothing)."""
    expected = {
        "seed": int,
        "config": dict,
        "graph": dict,
        "cycles": list,
        "episode_rewards": dict,
        "wall_s": (int, float),
    }
    for key, kind in expected.items():
        if not isinstance(log.get(key), kind):
            return f"{key!r} missing or not a {getattr(kind, '__name__', 'number')}"
    if not isinstance(log["graph"].get("fingerprint"), str):
        return "'graph.fingerprint' missing or not a string"
    rewards = log["episode_rewards"]
    if not all(isinstance(rewards.get(side), list) for side in ("robot", "human")):
        return "'episode_rewards' needs 'robot' and 'human' lists"
    for i, record in enumerate(log["cycles"], start=1):
        if not isinstance(record, dict) or not set(record) >= CYCLE_KEYS:
            return f"cycle record {i} lacks some of {', '.join(sorted(CYCLE_KEYS))}"
        if not isinstance(record["timesteps"], int):
            return f"cycle record {i}: 'timesteps' is not an integer"
    return ""
