"""Batch runs over a Dask cluster: nhdyn.dask.simulate_batch(client, model, ...) splits the runs
into chunks, one task per chunk; each worker rebuilds the model from its text (or built-in name)
and parameter overrides, never from a pickled C++ object, runs its chunk on its own cores with
nhdyn.simulate_batch, and the results are gathered and stacked as arrays in run order, exactly as
one nhdyn.simulate_batch on one machine would give them.

    from dask.distributed import Client, LocalCluster
    client = Client(LocalCluster(n_workers=2, threads_per_worker=1))
    runs = nhdyn.dask.simulate_batch(client, m, parameters={"v": np.linspace(0, 10, 1000)}, t_end=5)

On a real cluster, start `dask-scheduler` on one machine and `dask-worker tcp://SCHEDULER:8786`
on the others (each with nhdyn importable), then Client("tcp://SCHEDULER:8786"); see docs/python.md.
"""

import math
import re
import warnings

import numpy as np

import nhdyn

_models = {}  # on a worker: (source, overrides) -> Model, so chunks of one batch compile it once


def _model_on_worker(source, overrides):
    key = (source, overrides)
    model = _models.get(key)
    if model is None:
        builtin, text, file_name = source
        cpp_source = nhdyn._nhdyn.read_source(builtin) if builtin else nhdyn._nhdyn.source_from_text(text, file_name)
        model = nhdyn.Model(cpp_source, dict(overrides))
        if len(_models) > 16:
            _models.clear()
        _models[key] = model
    return model


def _run_chunk(source, overrides, names, values, q0, qd0, threads, options, start=0):
    """One task: a chunk of runs on one worker, the first being run `start` of the batch. Returns
    plain arrays and lists (picklable); an nhdyn error is returned too, as (type name, message with
    the batch's run numbers), so that the client raises it and the worker logs nothing (a failed
    task's log would repeat its arguments, the whole model text, once per chunk). Warnings are
    left to the client, which knows each run's number in the batch."""
    try:
        model = _model_on_worker(source, overrides)
        parameters = {name: values[:, j] for j, name in enumerate(names)}
        initial = {}
        if q0 is not None:
            initial["q"] = q0
        if qd0 is not None:
            initial["qd"] = qd0
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = nhdyn.simulate_batch(model, parameters=parameters or None, initial=initial or None, threads=threads,
                                     **options)
    except nhdyn.Error as error:
        return {"error": (type(error).__name__, _RUN.sub(lambda m: "run {}".format(start + int(m.group(1))),
                                                         str(error)))}
    return {"t": r.t, "q": r.q, "qd": r.qd, "qdd": r.qdd, "R": r.R, "residuals": r.residuals, "energy": r.energy,
            "contact_forces": r.contact_forces,
            "q_end": r.q_end, "qd_end": r.qd_end, "max_residual": r.max_residual, "ok": list(r.ok),
            "messages": r.messages, "summaries": r.summaries, "events": r.events, "threads": r.threads,
            "cpp_seconds": r.cpp_seconds}


# A message's "run K" (the library's numbering within the chunk's batch).
_RUN = re.compile(r"\brun (\d+)\b")


def _pad(array, rows):
    """array (runs, rows_k, ...) padded with NaN to `rows` rows."""
    if array.shape[1] == rows:
        return array
    shape = list(array.shape)
    shape[1] = rows
    out = np.full(shape, np.nan)
    out[:, : array.shape[1]] = array
    return out


def simulate_batch(client, model, parameters=None, initial=None, chunk_size=None, threads=1, **options):
    """Like nhdyn.simulate_batch, with the runs spread over the workers of a dask.distributed
    Client in chunks of `chunk_size` runs (default: about four chunks per worker), each chunk run
    on `threads` threads of its worker (threads=0: every core of the worker). Returns a
    nhdyn.BatchResult in run order."""
    names, values, q0, qd0, runs = nhdyn._batch_runs(model, parameters, initial)
    if runs == 0:
        raise nhdyn.InputError("simulate_batch: no runs (give at least one parameter value or initial state)")
    if chunk_size is None:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        chunk_size = max(1, math.ceil(runs / (4 * workers)))
    chunk_size = int(chunk_size)
    if chunk_size < 1:
        raise nhdyn.InputError("chunk_size = {}: give a positive number of runs per task".format(chunk_size))
    source = (model.source.builtin, model.source.text, model.source.file_name)
    overrides = tuple(sorted(model.overrides.items(), key=lambda item: item[0]))
    q0 = None if q0 is None else np.asarray(q0, dtype=float)
    qd0 = None if qd0 is None else np.asarray(qd0, dtype=float)
    futures = []
    for start in range(0, runs, chunk_size):
        stop = min(runs, start + chunk_size)
        futures.append(client.submit(
            _run_chunk, source, overrides, names, values[start:stop],
            None if q0 is None else q0[start:stop], None if qd0 is None else qd0[start:stop], threads, options,
            start, pure=False))
    parts = client.gather(futures)
    for part in parts:
        if "error" in part:
            kind, message = part["error"]
            raise getattr(nhdyn, kind, nhdyn.Error)(nhdyn._python_text(message))
    rows = max(np.shape(p["t"])[-1] for p in parts)
    longest = next(p["t"] for p in parts if np.ndim(p["t"]) == 1 and len(p["t"]) == rows) if all(
        np.ndim(p["t"]) == 1 for p in parts) else None
    if longest is not None and all(np.array_equal(p["t"], longest[: len(p["t"])]) for p in parts):
        t = longest
    else:  # the runs have their own times (events, a stop condition): t is per run, as in nhdyn.simulate_batch
        t = np.concatenate([_pad(p["t"] if np.ndim(p["t"]) == 2 else np.tile(p["t"], (len(p["ok"]), 1)), rows)
                            for p in parts])
    out = {"t": t}
    for key in ("q", "qd", "qdd", "R", "residuals"):
        out[key] = np.concatenate([_pad(p[key], rows) for p in parts])
    out["energy"] = None if parts[0]["energy"] is None else np.concatenate([_pad(p["energy"], rows) for p in parts])
    # A multibody model's contact forces and, with contact modes, NAME_mode, the slip, the gap,
    # work_friction and impact_loss: named by the model's columns["contact_forces"], as locally.
    out["contact_forces"] = None if parts[0]["contact_forces"] is None else np.concatenate(
        [_pad(p["contact_forces"], rows) for p in parts])
    for key in ("q_end", "qd_end", "max_residual"):
        out[key] = np.concatenate([p[key] for p in parts])
    for key in ("ok", "messages", "summaries", "events"):
        out[key] = [x for p in parts for x in p[key]]
    out["threads"] = max(p["threads"] for p in parts)
    out["cpp_seconds"] = sum(p["cpp_seconds"] for p in parts)
    # The warnings of the runs, numbered in the batch (the workers kept theirs), as nhdyn.simulate_batch gives them.
    for run, summary in enumerate(out["summaries"]):
        nhdyn._warn_constraints(model.name, summary, stacklevel=2, run=run)
    nhdyn._warn_unmet_stops(model.name, out["summaries"], stacklevel=2, batch=True)
    return nhdyn.BatchResult(out, {name: values[:, j] for j, name in enumerate(names)}, model.coordinates,
                             model._cpp.columns)
