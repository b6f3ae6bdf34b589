"""Stopping a training run and continuing it where it stopped (`train --resume`).

A run on two cores spans working days, and a machine can go away in the
middle of one. So the checkpoint that `train` writes (at the end of every
epoch, every SAVE_EVERY_S seconds within one, and when the run ends) carries,
beside the weights, what the loop needs to go on as if it had never stopped:
the optimiser's moments, the weights as trained and their average, the step,
the training seconds spent, the epoch's frame order and the place in it, the
log so far and the run's own arguments.

`touch OUT/STOP` ends a run at its next step: it saves, exports what it has
(as at the end of its budget) and removes the file. `train --resume OUT`
then continues the same schedule: the learning rate and the augmentation's
curriculum are functions of the share of the budget spent, so a resumed run
decays where the uninterrupted one would have. `--minutes` with it sets a
new total budget (a run planned over several sessions can be lengthened).

Not restored: the augmentation's random draws (each worker's generator is
seeded again from the seed, its rank and the step), so a resumed run is not
bit for bit the uninterrupted one; the frame order, the weights, the
optimiser, the average and the schedule are.
"""

from __future__ import annotations

import os
import pickle

import torch

SAVE_EVERY_S = 600.0  # a run killed without STOP loses at most this much
STOP_FILE = "STOP"
FORMAT = 1


def record(plan: dict, opt, perm_gen: torch.Generator, step: int, epoch: int, elapsed_s: float,
           perm: torch.Tensor | None, offset: int, log_rows: list) -> dict:
    """What a checkpoint needs to continue the run: perm and offset are the
    current epoch's frame order and the first batch not yet trained (perm
    None: the epoch is complete, the next one draws a new order)."""
    return dict(format=FORMAT, args=plan["args"], frames=int(len(plan["tr"])),
                budget_s=plan["budget"], optimizer=opt.state_dict(),
                perm_gen=perm_gen.get_state(), step=step, epoch=epoch, elapsed_s=elapsed_s,
                perm=None if perm is None else perm.clone(), offset=offset,
                log_rows=[dict(r) for r in log_rows])


def load(path: str) -> tuple[dict, dict]:
    """The checkpoint of the run in folder `path` (or the checkpoint file
    itself) and its resume record; a clear error for anything else."""
    ckpt = os.path.join(path, "checkpoint.pth") if os.path.isdir(path) else path
    if not os.path.exists(ckpt):
        raise ValueError(f"{path}: no checkpoint.pth to resume (the run saves its first one "
                         f"{SAVE_EVERY_S / 60:.0f} minutes in, or at its first epoch's end)")
    try:
        checkpoint = torch.load(ckpt, map_location="cpu")
    except (RuntimeError, EOFError, pickle.UnpicklingError) as e:
        raise ValueError(f"{ckpt}: not readable as a checkpoint (file truncated?): {e}") from e
    rec = checkpoint.get("resume") if isinstance(checkpoint, dict) else None
    if not isinstance(rec, dict) or rec.get("format") != FORMAT:
        raise ValueError(f"{ckpt}: written before runs could be resumed (no resume record): "
                         "continue from its weights with --init instead (a new schedule)")
    return checkpoint, rec


def train_arguments(rec: dict, out: str, minutes: float | None) -> dict:
    """train()'s keyword arguments that continue the recorded run into `out`;
    minutes: a new total budget, which must exceed the minutes spent."""
    spent = rec["elapsed_s"] / 60.0
    total = rec["budget_s"] / 60.0 if minutes is None else minutes
    if total <= spent:
        raise ValueError(f"the run has spent {spent:.1f} of its {total:.1f} minutes: give "
                         f"--minutes more than {spent:.1f} (the new total budget) to go on")
    args = rec["args"]
    for drive in [*args["data"], *([args["val"]] if args["val"] else [])]:
        if not os.path.isdir(drive):
            raise ValueError(f"the run's drive {drive} is not here: resume on the machine that "
                             "has its drives (or render them again), or start a new schedule "
                             "from its weights with --init")
    return dict(args, out=out, minutes=total)


def resume(path: str, minutes: float | None = None, log=print):
    """Continue the run whose folder (or checkpoint) is `path`, in that
    folder; returns train()'s model and configuration, and the arguments it
    was called with (the run's drives, folder and validation drive)."""
    from .train import train

    checkpoint, rec = load(path)
    out = path if os.path.isdir(path) else os.path.dirname(os.path.abspath(path))
    kwargs = train_arguments(rec, out, minutes)
    log(f"train: resuming {out} at step {rec['step']}, {rec['elapsed_s'] / 60:.1f} of "
        f"{kwargs['minutes']:.1f} minutes")
    model, cfg = train(**kwargs, log=log, resume=(checkpoint, rec))
    return model, cfg, kwargs
