"""Scenarios: a system, its uncertainty sets, a disturbance generator, reproducible seeds."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .. import examples
from ..exceptions import ArgumentError, InvalidValueError
from ..geometry import ConstrainedZonotope
from ..models.linear import LinearSystem

__all__ = ["EXAMPLE_SYSTEMS", "GENERATORS", "Scenario", "Trajectory", "band_limited_noise",
           "rng_for_run"]

#: Example systems by name (used by configuration files and the command line).
EXAMPLE_SYSTEMS: dict[str, Callable[[], LinearSystem]] = {
    "chang2006": examples.chang2006,
    "cgl1": examples.chen_gao_lin_example1,
    "cgl2-20ms": lambda: examples.chen_gao_lin_example2("20ms"),
    "cgl2-1ms": lambda: examples.chen_gao_lin_example2("1ms"),
    "cgl4": examples.chen_gao_lin_example4,
    "cgl5": examples.chen_gao_lin_example5,
}

#: Disturbance generators.
GENERATORS = ("random_walk", "steps", "sinusoid", "gaussian")


def rng_for_run(base_seed: int, run: int) -> np.random.Generator:
    """Generator of run ``run``: ``SeedSequence(base_seed, spawn_key=(run,))``.

    Every run is reproducible on its own, independently of how many runs are
    made or in which order (or on which worker) they execute.

    Parameters
    ----------
    base_seed : int
        The campaign's seed.
    run : int
        The run index.
    """
    return np.random.default_rng(np.random.SeedSequence(base_seed, spawn_key=(int(run),)))


def band_limited_noise(power: float | Any, dt: float, size: int,
                       rng: np.random.Generator) -> NDArray[np.float64]:
    """Samples of Simulink's *Band-Limited White Noise* block held at the sampling time.

    The block draws Gaussian samples of variance ``power / dt`` (``power`` is the
    height of the power spectral density, ``dt`` the block's sample time), so that
    the sampled sequence has the PSD of continuous white noise of that power. This
    is how Chen-Gao-Lin's Example 2 specifies its measurement noise (powers
    ``2e-8`` and ``2e-1``); at ``dt = 1 ms`` the second output's standard deviation
    is ``sqrt(0.2 / 0.001) ~ 14``.

    Parameters
    ----------
    power : float or array_like, shape (l,)
        Noise power per channel (nonnegative).
    dt : float
        Sample time of the block (positive).
    size : int
        Number of samples.
    rng : numpy.random.Generator
        The random generator.

    Returns
    -------
    ndarray, shape (size, l)
        The noise samples (one column per channel; a scalar power gives one column).
    """
    pw = np.atleast_1d(np.asarray(power, float))
    if pw.ndim != 1 or np.any(pw < 0) or not np.all(np.isfinite(pw)):
        raise InvalidValueError(f"power must be nonnegative and finite per channel, got {power!r}")
    if not (np.isfinite(dt) and dt > 0):
        raise InvalidValueError(f"dt must be positive, got {dt!r}")
    return rng.standard_normal((int(size), pw.size)) * np.sqrt(pw / dt)


@dataclass(frozen=True)
class Trajectory:
    """One simulated record: ``Y (N, l)``, true ``D (N, q)``, ``X (N, n)``, inputs ``U``.

    Attributes
    ----------
    Y : ndarray, shape (N, l)
        Measured outputs.
    D : ndarray, shape (N, q)
        True disturbance.
    X : ndarray, shape (N, n)
        True state.
    U : ndarray, shape (N, p) or None
        Applied inputs.
    """

    Y: NDArray[np.float64]
    D: NDArray[np.float64]
    X: NDArray[np.float64]
    U: NDArray[np.float64] | None


@dataclass(frozen=True)
class Scenario:
    """A simulation scenario.

    Attributes
    ----------
    system : str, path or LinearSystem
        A name in :data:`EXAMPLE_SYSTEMS`, a model file (any format
        :func:`setobs.io.load_model` reads: ``Phi, G, Xi`` or ``A, B, C, D``
        with the disturbance channels), or a :class:`LinearSystem` (the
        user's own plant).
    horizon : int
        Number of steps ``N``.
    increment : float
        Box radius of the disturbance increment ``|dd_i| <= increment`` (the
        SMFDO's increment set; Li-Cong-Dong eq. (27) uses 1).
    x0_box : float or None
        ``|x0_i| <= x0_box`` (the SMFDO's initial state set); ``None``: ``R^n``.
    generator : str
        ``"random_walk"`` (uniform increments in the box: the set-membership
        paper's case), ``"steps"`` (jumps of at most ``increment`` at random
        times), ``"sinusoid"`` (Fu-Wang's ``d*(k)``), ``"gaussian"`` (i.i.d.
        Gaussian, MB-ESO Example 1: means 1, 2, 3, variances 0.1, 0.2, 0.3).
    noise_std : float
        Standard deviation of additive measurement noise (0: none; the SMFDO
        assumes none, so its guarantee does not cover noisy data).
    d0 : tuple of float, optional
        Initial disturbance (default: generator-specific).
    """

    system: str | LinearSystem = "chang2006"
    horizon: int = 100
    increment: float = 1.0
    x0_box: float | None = 1.0
    generator: str = "random_walk"
    noise_std: float = 0.0
    d0: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        if isinstance(self.system, PathLike):
            object.__setattr__(self, "system", str(self.system))
        if isinstance(self.system, LinearSystem):
            pass
        elif not isinstance(self.system, str):
            raise ArgumentError(f"system must be an example name, a model file or a LinearSystem, "
                                f"got {type(self.system).__name__}")
        elif self.system not in EXAMPLE_SYSTEMS and not Path(self.system).is_file():
            raise InvalidValueError(f"unknown system {self.system!r}: neither an example "
                                 f"({', '.join(sorted(EXAMPLE_SYSTEMS))}) nor a model file")
        if self.generator not in GENERATORS:
            raise InvalidValueError(f"unknown generator {self.generator!r}; choose from "
                                 f"{list(GENERATORS)}")
        if int(self.horizon) != self.horizon or self.horizon < 1:
            raise InvalidValueError(f"horizon must be a positive integer, got {self.horizon!r}")
        if not self.increment > 0:
            raise InvalidValueError(f"increment must be positive, got {self.increment}")
        if self.noise_std < 0:
            raise InvalidValueError(f"noise_std must be nonnegative, got {self.noise_std}")

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (for metadata files); a :class:`LinearSystem` becomes its
        matrices."""
        if not isinstance(self.system, LinearSystem):
            return asdict(self)
        sys = self.system
        out = asdict(replace(self, system="chang2006"))
        out["system"] = {"Phi": sys.Phi.tolist(), "G": sys.G.tolist(), "Xi": sys.Xi.tolist(),
                         "Gamma": sys.Gamma.tolist(), "Du": sys.Du.tolist(), "dt": sys.dt}
        return out

    def build_system(self) -> LinearSystem:
        """The scenario's :class:`LinearSystem`."""
        if isinstance(self.system, LinearSystem):
            return self.system
        if self.system in EXAMPLE_SYSTEMS:
            return EXAMPLE_SYSTEMS[self.system]()
        from ..io import load_model

        return load_model(self.system)

    def increment_set(self, q: int) -> ConstrainedZonotope:
        """``{dd : |dd_i| <= increment}``.

        Parameters
        ----------
        q : int
            Number of disturbance channels.
        """
        r = np.full(q, float(self.increment))
        return ConstrainedZonotope.from_box(-r, r)

    def initial_state_set(self, n: int) -> ConstrainedZonotope | None:
        """``{x0 : |x0_i| <= x0_box}`` (``None`` for ``R^n``).

        Parameters
        ----------
        n : int
            State dimension.
        """
        if self.x0_box is None:
            return None
        r = np.full(n, float(self.x0_box))
        return ConstrainedZonotope.from_box(-r, r)

    def disturbance(self, q: int, rng: np.random.Generator) -> NDArray[np.float64]:
        """The disturbance sequence ``D (N, q)``.

        Parameters
        ----------
        q : int
            Number of disturbance channels.
        rng : numpy.random.Generator
            Random stream.
        """
        N, r = int(self.horizon), float(self.increment)
        if self.generator == "random_walk":
            d0 = np.zeros(q) if self.d0 is None else np.asarray(self.d0, float)
            steps = rng.uniform(-r, r, size=(N - 1, q))
            return np.vstack([d0, d0 + np.cumsum(steps, axis=0)])
        if self.generator == "steps":
            d0 = np.zeros(q) if self.d0 is None else np.asarray(self.d0, float)
            jumps = np.zeros((N - 1, q))
            mask = rng.random(size=(N - 1, q)) < 0.05
            jumps[mask] = rng.uniform(-r, r, size=int(mask.sum()))
            return np.vstack([d0, d0 + np.cumsum(jumps, axis=0)])
        if self.generator == "sinusoid":
            k = np.arange(N)[:, None]
            base = np.hstack([0.3 * np.sin(0.1 * k) + 0.5 * np.cos(0.03 * k),
                              0.2 * np.cos(0.05 * k) + 2.0])
            reps = -(-q // 2)
            out = np.tile(base, (1, reps))[:, :q]
            return out + (0.0 if self.d0 is None else np.asarray(self.d0, float))
        # gaussian
        mean = np.resize(np.array([1.0, 2.0, 3.0]), q)
        var = np.resize(np.array([0.1, 0.2, 0.3]), q)
        return rng.normal(mean, np.sqrt(var), size=(N, q))

    def simulate(self, rng: np.random.Generator) -> Trajectory:
        """Simulate ``x+ = Phi x + G d``, ``y = Xi x (+ noise)`` from a random ``x0`` in the set.

        Parameters
        ----------
        rng : numpy.random.Generator
            Random stream (initial state, disturbance, noise).
        """
        sys = self.build_system()
        D = self.disturbance(sys.q, rng)
        x = (rng.uniform(-self.x0_box, self.x0_box, sys.n) if self.x0_box is not None
             else rng.normal(size=sys.n))
        U = np.zeros((self.horizon, sys.p)) if sys.p else None
        Y, X = sys.simulate(D, U, x0=x)
        if self.noise_std > 0:
            Y = Y + rng.normal(0.0, self.noise_std, size=Y.shape)
        return Trajectory(Y, D, X, U)
