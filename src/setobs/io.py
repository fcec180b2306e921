"""Models and measured records from files (JSON, YAML, .npz, .mat, CSV).

Model files hold matrices in either naming:

* ``Phi, G, Xi`` (+ ``Gamma``, ``Du``): the discrete-time notation of the papers
  (aliases: ``E``/``F`` for ``G``, ``B`` for ``Gamma`` when a ``G`` is given);
* ``A, B, C, D`` (python-control / MATLAB) with the disturbances stated by
  ``G`` (then ``B`` holds the control inputs) or by ``disturbance_inputs``
  (indices or names of ``B``'s columns).

Optional keys: ``Ts`` (or ``dt``) the sampling time; ``continuous: true`` for
a continuous-time model, discretised with a zero-order hold at ``Ts`` (MATLAB's
``Ts = 0`` also means continuous); ``state_names``, ``input_names``,
``output_names``, ``disturbance_names`` (lists of names: the columns of a result's
table, ``<name>_lo`` and ``<name>_hi``, and the plots' labels; defaults ``x0, x1, ...``,
``u0, ...``, ``y0, ...``, ``d0, ...``); ``units``, a mapping from signal names to
units (``{theta: rad, omega: rad/s, tau_L: N m}``, read by :func:`model_units`; the
CLI's plots label their axes with them). Any other key is refused, with the known
keys listed (a misspelt ``state_name`` is an error, not a silent default). Anything
wrong raises :class:`ModelFileError` with one line saying what and where.
"""

from __future__ import annotations

import csv
import json
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._lazy import optional_import
from .exceptions import ModelFileError, RecordNotFoundError
from .models.linear import LinearSystem

__all__ = ["RECORDS", "ModelFileError", "Record", "find_record", "load_model", "load_record",
           "model_units"]

#: The measured records the guide and the notebooks use: where each comes from. None is
#: shipped with the package (the sources carry no licence to redistribute them).
RECORDS: Mapping[str, str] = MappingProxyType({
    "hsm150/idf_pos_0.06_1.mat": (
        "the HSM150 servo-motor identification record: download "
        "Data/Identification/idf_pos_0.06_1.mat from the public repository "
        "https://github.com/malik-robert/HSM150-data"),
})

_KEYS = {"Phi": ("Phi", "A", "A0"), "G": ("G", "E", "E0", "F"), "Xi": ("Xi", "C", "C0"),
         "Gamma": ("Gamma", "B", "B0"), "Du": ("Du", "D")}
_NAME_KEYS = ("state_names", "input_names", "output_names", "disturbance_names")
#: Every key a model file may have (the matrices under any of their names).
MODEL_KEYS = tuple(sorted({k for names in _KEYS.values() for k in names}
                          | {"Ts", "dt", "continuous", "disturbance_inputs", "units",
                             *_NAME_KEYS}, key=str.lower))

def _read_mapping(p: Path) -> dict[str, Any]:
    if not p.exists():
        raise ModelFileError(f"no such file: {p}")
    suffix = p.suffix.lower()
    try:
        if suffix == ".json":
            data = json.loads(p.read_text())
        elif suffix in (".yaml", ".yml"):
            yaml = optional_import("yaml", extra="yaml", feature="reading a .yaml model file")
            data = yaml.safe_load(p.read_text())
        elif suffix == ".npz":
            with np.load(p, allow_pickle=False) as z:
                data = {k: z[k] for k in z.files}
        elif suffix == ".mat":
            from scipy.io import loadmat

            data = {k: v for k, v in loadmat(p, squeeze_me=False).items()
                    if not k.startswith("__")}
        else:
            raise ModelFileError(f"unsupported file type {suffix!r} (use .json, .yaml, .npz "
                                 "or .mat)")
    except ModelFileError:
        raise
    except Exception as exc:  # parse errors of any reader
        raise ModelFileError(f"could not read {p}: {str(exc).splitlines()[0]}") from None
    if not isinstance(data, dict):
        raise ModelFileError(f"{p} must contain a mapping of matrices")
    return data


def _matrix(data: dict, key: str) -> NDArray | None:
    for name in _KEYS[key]:
        if name in data:
            try:
                M = np.asarray(data[name], dtype=float)
            except (TypeError, ValueError):
                raise ModelFileError(f"matrix {name!r} must be a numeric matrix (a list of rows "
                                     f"of numbers), got {str(data[name])[:60]!r}") from None
            if M.ndim > 2:
                raise ModelFileError(f"matrix {name!r} must be 2-D, got {M.ndim} dimensions")
            return np.atleast_2d(M) if M.size else None
    return None


def _scalar(data: dict, key: str) -> Any:
    v = data[key]
    if isinstance(v, np.ndarray):
        if v.size != 1:
            raise ModelFileError(f"{key!r} must be a single value, got shape {v.shape}")
        v = v.reshape(-1)[0]
        if isinstance(v, np.generic):
            v = v.item()
    return v


def _names(data: dict, key: str) -> list[str] | None:
    if key not in data:
        return None
    v = data[key]
    if isinstance(v, str):
        return [v]
    if isinstance(v, np.ndarray):  # .mat char matrix (padded) / cell array, .npz strings
        return [str(np.asarray(x).reshape(-1)[0] if isinstance(x, np.ndarray) else x).strip()
                for x in np.asarray(v, dtype=object).reshape(-1)]
    if isinstance(v, list | tuple):
        return [str(x) for x in v]
    raise ModelFileError(f"{key!r} must be a list of names, got {v!r}")


def load_model(path: str | Path, *, dt: float | None = None) -> LinearSystem:
    """A :class:`LinearSystem` from a model file (see the module docstring).

    Parameters
    ----------
    path : str or Path
        ``.json``, ``.yaml``/``.yml``, ``.npz`` or ``.mat``.
    dt : float, optional
        Sampling time used to discretise a continuous-time model that has no
        ``Ts`` (e.g. the record's); for a discrete model it must agree with
        the file's ``Ts``.

    Raises
    ------
    ModelFileError
        Unreadable file, missing or ill-shaped matrices, disturbances not
        stated, conflicting sampling times.
    """
    return _load_model_and_units(path, dt=dt)[0]


def _load_model_and_units(path: str | Path, *, dt: float | None = None
                          ) -> tuple[LinearSystem, dict[str, str]]:
    """:func:`load_model` and :func:`model_units` from one reading of the file."""
    p = Path(path)
    data = _read_mapping(p)
    try:
        sys_ = _system_from_mapping(data, dt, p)
    except ModelFileError:
        raise
    except (ValueError, TypeError) as exc:  # DimensionError and friends: one line
        raise ModelFileError(f"{p}: {exc}") from None
    return sys_, _units(data, sys_, p)


def _check_keys(data: dict, p: Path) -> None:
    unknown = sorted(set(data) - set(MODEL_KEYS))
    if unknown:
        import difflib

        hints = [f"{k!r} (did you mean {m[0]!r}?)" if (m := difflib.get_close_matches(
            k, MODEL_KEYS, n=1)) else repr(k) for k in unknown]
        raise ModelFileError(f"{p}: unknown key(s) {', '.join(hints)}; a model file's keys "
                             f"are {', '.join(MODEL_KEYS)}")


def _system_from_mapping(data: dict, dt: float | None, p: Path) -> LinearSystem:
    _check_keys(data, p)
    Phi = _matrix(data, "Phi")
    Xi = _matrix(data, "Xi")
    if Phi is None:
        raise ModelFileError(f"{p}: missing the state matrix (accepted names: Phi, A)")
    if Xi is None:
        raise ModelFileError(f"{p}: missing the output matrix (accepted names: Xi, C)")
    G, B, D = _matrix(data, "G"), _matrix(data, "Gamma"), _matrix(data, "Du")
    Ts = None
    for key in ("Ts", "dt"):
        if key in data:
            try:
                Ts = float(_scalar(data, key))
            except (TypeError, ValueError):
                raise ModelFileError(f"{p}: {key} must be a number") from None
    continuous = bool(_scalar(data, "continuous")) if "continuous" in data else False
    if Ts is not None and Ts == 0.0:  # MATLAB: Ts = 0 is a continuous-time model
        continuous, Ts = True, None
    if Ts is not None and Ts < 0:  # MATLAB: Ts = -1, discrete with unspecified sampling
        Ts = None
    if dt is not None and Ts is not None and abs(dt - Ts) > 1e-9 * Ts:
        raise ModelFileError(f"{p}: the model's Ts = {Ts:g} differs from the record's "
                             f"sampling time {dt:g}")
    Ts = dt if Ts is None else Ts
    if continuous and Ts is None:
        raise ModelFileError(f"{p}: a continuous-time model needs a sampling time (Ts in "
                             "the file, or --dt / the record's time column)")
    dist = None
    if "disturbance_inputs" in data:
        v = data["disturbance_inputs"]
        if isinstance(v, np.ndarray):
            v = v.reshape(-1).tolist() if v.dtype.kind in "iuf" else _names(
                data, "disturbance_inputs")
        dist = v
    if G is None and dist is None:
        raise ModelFileError(
            f"{p}: the disturbance channels are not stated: give G (accepted names: G, E, F), "
            "or disturbance_inputs (the columns of B that are disturbances)")
    names = {k: _names(data, k) for k in _NAME_KEYS}
    return LinearSystem.from_matrices(A=Phi, C=Xi, B=B, D=D, G=G, disturbance_inputs=dist,
                                      dt=Ts, continuous=continuous, **names)


def _units(data: dict, sys_: LinearSystem, p: Path) -> dict[str, str]:
    if "units" not in data:
        return {}
    v = data["units"]
    if not isinstance(v, dict) or not all(isinstance(u, str | int | float)
                                          for u in v.values()):
        raise ModelFileError(f"{p}: units must be a mapping from signal names to units "
                             f"(e.g. {{theta: rad, omega: rad/s}}), got {str(v)[:60]!r}")
    known = [*sys_.state_names, *sys_.output_names, *sys_.input_names,
             *sys_.disturbance_names]
    bad = sorted(str(k) for k in v if str(k) not in known)
    if bad:
        raise ModelFileError(f"{p}: units names unknown signal(s) {bad}; the model's "
                             f"signals are {', '.join(dict.fromkeys(known))}")
    return {str(k): str(u) for k, u in v.items()}


def model_units(path: str | Path, *, dt: float | None = None) -> dict[str, str]:
    """The ``units`` of a model file: ``{signal name: unit}`` (empty without the key).

    Parameters
    ----------
    path : str or Path
        The model file (as for :func:`load_model`).
    dt : float, optional
        As for :func:`load_model` (the model is built to check the names).

    Returns
    -------
    dict of str to str
        The unit of each signal named under ``units`` (states, outputs, inputs,
        disturbances by their names).

    Raises
    ------
    ModelFileError
        As :func:`load_model`; also when ``units`` is not a mapping or names a
        signal the model does not have.
    """
    return _load_model_and_units(path, dt=dt)[1]


@dataclass(frozen=True)
class Record:
    """A measured record: outputs ``Y (N, l)``, inputs ``U (N, p)`` or ``None``, time ``t``.

    Attributes
    ----------
    dt : float or None
        Sampling time (from the time column or given).
    output_names, input_names : tuple of str
        Column names (or ``col<i>``).
    Y : ndarray, shape (N, l)
        Measured outputs (NaN: missing).
    U : ndarray, shape (N, p) or None
        Applied inputs.
    t : ndarray, shape (N,)
        Time stamps (``k dt``, or the step ``k`` without a sampling time).
    """

    Y: NDArray[np.float64]
    U: NDArray[np.float64] | None
    t: NDArray[np.float64]
    dt: float | None
    output_names: tuple[str, ...]
    input_names: tuple[str, ...]


def _read_table(p: Path, variable: str | None) -> tuple[NDArray, list[str]]:
    """All columns of a record file as a float array, and their names."""
    if not p.exists():
        raise ModelFileError(f"no such file: {p}")
    suffix = p.suffix.lower()
    if suffix in (".csv", ".txt", ".tsv"):
        try:
            with p.open(newline="") as f:
                sample = f.read(4096)
                f.seek(0)
                delim = "\t" if suffix == ".tsv" else (csv.Sniffer().sniff(sample, ",;\t ")
                                                      .delimiter if sample else ",")
                rows = [r for r in csv.reader(f, delimiter=delim) if r and any(c.strip()
                                                                                 for c in r)]
        except (OSError, csv.Error, UnicodeDecodeError) as exc:
            raise ModelFileError(f"could not read {p}: {exc}") from None
        if not rows:
            raise ModelFileError(f"{p} is empty")
        header = None
        try:
            [float(c) for c in rows[0]]
        except ValueError:
            header, rows = [c.strip() for c in rows[0]], rows[1:]
        try:
            arr = np.array([[float(c) if c.strip() not in ("", "nan", "NaN", "NA") else np.nan
                             for c in r] for r in rows], dtype=float)
        except ValueError as exc:
            raise ModelFileError(f"{p}: non-numeric entry ({exc})") from None
        if arr.ndim != 2 or (header is not None and arr.shape[1] != len(header)):
            raise ModelFileError(f"{p}: rows of different lengths")
        return arr, header or [f"col{i}" for i in range(arr.shape[1])]
    data = _read_mapping(p)
    arrays = {k: v for k, v in data.items() if isinstance(v, np.ndarray) and v.ndim >= 1
              and v.dtype.kind in "iuf" and v.size > 1}
    if variable is None:
        two_d = [k for k, v in arrays.items() if np.squeeze(v).ndim == 2]
        if len(two_d) != 1:
            raise ModelFileError(f"{p}: name the data matrix with --variable (numeric "
                                 f"arrays: {sorted(arrays)})")
        variable = two_d[0]
    if variable not in arrays:
        raise ModelFileError(f"{p}: no numeric variable {variable!r} (numeric arrays: "
                             f"{sorted(arrays)})")
    arr = np.asarray(arrays[variable], dtype=float)
    arr = arr.reshape(-1, 1) if arr.ndim == 1 else np.squeeze(arr)
    if arr.ndim != 2:
        raise ModelFileError(f"{p}: {variable!r} must be a 2-D matrix (samples x signals)")
    return arr, [f"col{i}" for i in range(arr.shape[1])]


def _columns(what: str, spec: Any, names: list[str]) -> list[int]:
    if spec is None:
        return []
    items = spec.split(",") if isinstance(spec, str) else list(spec)
    out = []
    for s in items:
        s = str(s).strip()
        if s in names:
            out.append(names.index(s))
            continue
        try:
            i = int(s)
        except ValueError:
            raise ModelFileError(f"{what}: no column {s!r} (columns: {names})") from None
        if not 0 <= i < len(names):
            raise ModelFileError(f"{what}: column index {i} out of range (0..{len(names) - 1})")
        out.append(i)
    return out


def round_time(x: float) -> float:
    """A time or sampling time at 12 significant digits: a time column printed in
    milliseconds gives steps like 0.0009999999999998899, which is 0.001 s.

    Parameters
    ----------
    x : float
        Seconds.
    """
    return float(f"{float(x):.12g}")


def load_record(path: str | Path, *, outputs: Any, inputs: Any = None, time: Any = None,
                dt: float | None = None, variable: str | None = None,
                decimate: int = 1) -> Record:
    """A measured record from CSV (header optional), ``.mat`` or ``.npz``.

    Parameters
    ----------
    path : str or Path
    outputs, inputs : str or sequence
        Columns (names from the CSV header, or 0-based indices; a string may
        list several separated by commas).
    time : str or int, optional
        Time column: sets ``dt`` (uniform sampling is checked, 1 % tolerance).
    dt : float, optional
        Sampling time when there is no time column.
    variable : str, optional
        Name of the data matrix in a ``.mat``/``.npz`` file (default: its only
        2-D numeric array).
    decimate : int
        Keep every ``decimate``-th sample (``dt`` scales accordingly).

    Raises
    ------
    ModelFileError
        One line saying what is wrong.
    """
    p = Path(path)
    arr, names = _read_table(p, variable)
    out_idx = _columns("outputs", outputs, names)
    if not out_idx:
        raise ModelFileError("name at least one output column")
    in_idx = _columns("inputs", inputs, names)
    if isinstance(decimate, bool) or int(decimate) != decimate or decimate < 1:
        raise ModelFileError(f"decimate must be a positive integer, got {decimate!r}")
    t = None
    if time is not None:
        (ti,) = _columns("time", [time], names)
        t = arr[:, ti]
        steps = np.diff(t)
        if t.size < 2 or not np.isfinite(t).all() or (steps <= 0).any():
            raise ModelFileError("the time column must be finite and increasing")
        med = float(np.median(steps))
        if np.abs(steps - med).max() > 0.01 * med:
            raise ModelFileError(f"non-uniform sampling in the time column (steps from "
                                 f"{steps.min():g} to {steps.max():g} s)")
        if dt is not None and abs(dt - med) > 0.01 * med:
            raise ModelFileError(f"--dt {dt:g} disagrees with the time column ({med:g} s)")
        dt = round_time(med)
    if dt is not None and not dt > 0:
        raise ModelFileError(f"dt must be positive, got {dt}")
    sl = slice(None, None, int(decimate))
    arr = arr[sl]
    N = arr.shape[0]
    if t is None:
        t = np.arange(N) * (dt * decimate if dt else 1.0)
    else:
        t = t[sl]
    U = arr[:, in_idx] if in_idx else None
    if U is not None and not np.isfinite(U).all():
        raise ModelFileError("the input columns must be finite (a missing input is unknown "
                             "excitation, not a missing measurement)")
    return Record(arr[:, out_idx], U, t, None if dt is None else dt * decimate,
                  tuple(names[i] for i in out_idx), tuple(names[i] for i in in_idx))


def find_record(name: str, *, roots: list[str | Path] | None = None) -> Path:
    """The path of a measured record that is not shipped with the package.

    Looked up as ``<root>/<name>`` in ``$SETOBS_DATA``, then in the folder
    ``shared/data`` beside a repository checkout that holds the current directory
    (found from the current directory upwards), or in ``roots`` when given.

    Parameters
    ----------
    name : str
        The record's path below the data folder, e.g. ``"hsm150/idf_pos_0.06_1.mat"``
        (:data:`RECORDS` lists the known ones and their sources).
    roots : list of str or Path, optional
        Folders to look in instead of the default ones.

    Returns
    -------
    Path
        The first existing ``<root>/<name>``.

    Raises
    ------
    RecordNotFoundError
        When no folder holds it: the message says where the record comes from and how
        to point setobs at it.
    """
    if roots is None:
        cwd = Path.cwd()
        repos = [p for p in [cwd, *cwd.parents] if (p / "pyproject.toml").is_file()]
        roots = [r for r in [os.environ.get("SETOBS_DATA"),
                             *(p.parent / "shared" / "data" for p in repos[:1])] if r]
    for root in roots:
        path = Path(root) / name
        if path.is_file():
            return path
    source = RECORDS.get(name, "a record this package does not ship")
    folder = Path(name).parent
    raise RecordNotFoundError(
        f"{name} not found (looked in: {', '.join(str(r) for r in roots) or 'no folder'}). "
        f"It is {source}. What to do: put it in <folder>/{folder}/ and set the environment "
        "variable SETOBS_DATA=<folder>")
