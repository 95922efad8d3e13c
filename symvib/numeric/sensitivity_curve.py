"""The curve as exact sensitivities see it: its kernels, its jets, and the parameters of ``wrt``
(physics.md, "Sensitivities").

:func:`resolve_wrt` turns the names a caller gives into parameters: the scene's
(:data:`PARAMETERS`, or their scene-file names such as ``physics.restitution``) and the curve's
(``p``, or ``parameters.p``).  A name that is both a scene parameter and a curve parameter
(a user curve with a parameter ``k``) is refused: ``parameters.k`` names the curve's,
``physics.restitution`` the scene's.

:class:`CurveFunctions` evaluates the curve's kernels at arrays of ``q`` with its parameters bound,
and the explicit derivatives at fixed ``q`` that the implicit function theorem needs, one column
per parameter of ``wrt``: ``d F_s' / d mu`` (in closed form) and, for a curve parameter ``a``, the
generated ``d/da`` of ``x, z, alpha, alpha', h, h', kappa`` and ``F_s'`` (physics.md,
"Sensitivities" 9).  Those and ``kappa'`` (item 8) come from the curve's jets module
(:mod:`symvib.numeric.jet_kernels`), loaded only when first asked for.

Examples
--------
>>> from symvib.numeric.scene import resolve_scene
>>> resolve_wrt(resolve_scene("paper-parabola"), ("mu", "parameters.p", "initial.qdot"))
(('mu', 'scene', 'mu'), ('parameters.p', 'curve', 'p'), ('initial.qdot', 'scene', 'qdot0'))
"""
from __future__ import annotations

import numpy as np

__all__ = ["PARAMETERS", "SCENE_FIELDS", "resolve_wrt", "parameter_value", "with_parameters", "CurveFunctions"]

#: Scene parameters a run's events can be differentiated with respect to.
PARAMETERS = ("mu", "k", "qdot0", "q0", "left", "right")
#: Scene-file names of :data:`PARAMETERS` (the sweep's ``--vary`` names): unambiguous where a curve
#: parameter has a short name too.
SCENE_FIELDS = {"physics.mu": "mu", "physics.restitution": "k", "initial.qdot": "qdot0", "initial.q": "q0",
                "limiters.left": "left", "limiters.right": "right"}
#: Prefix that names a curve parameter whatever its name.
CURVE_PREFIX = "parameters."
#: The curve's kernels of ``q`` alone that :class:`CurveFunctions` evaluates (its methods of the same names).
GEOMETRY = ("h", "dh", "alpha", "dalpha", "dx", "dz", "z", "x", "kappa")


def resolve_wrt(scene, wrt, field: str = "wrt") -> tuple:
    """``(name as given, "scene" or "curve", parameter)`` of each name of ``wrt``.

    Raises
    ------
    ValueError
        Naming ``field``: not a sequence of names, an unknown, repeated or ambiguous name (both a
        scene parameter and a curve parameter), or a limiter the scene does not have.
    """
    curve_params = [n for n, _ in scene.params]
    known = ", ".join(PARAMETERS + tuple(curve_params))
    if isinstance(wrt, str):   # one name, not its letters
        wrt = (wrt,)
    try:
        wrt = tuple(wrt)
    except TypeError:
        raise ValueError(f"{field}: expected names of parameters from {known}, got {type(wrt).__name__}") from None
    out = []
    for name in wrt:
        if not isinstance(name, str):
            raise ValueError(f"{field}: {name!r} is not a parameter name ({known})")
        if name in SCENE_FIELDS:
            out.append((name, "scene", SCENE_FIELDS[name]))
        elif name.startswith(CURVE_PREFIX) and name[len(CURVE_PREFIX):] in curve_params:
            out.append((name, "curve", name[len(CURVE_PREFIX):]))
        elif name in PARAMETERS and name in curve_params:
            scene_field = next(f for f, p in SCENE_FIELDS.items() if p == name)
            raise ValueError(f"{field}: {name!r} is ambiguous: both the scene's {name} and a parameter of curve "
                             f"'{scene.shape.name}'; name the curve's {CURVE_PREFIX}{name}, the scene's {scene_field}")
        elif name in PARAMETERS:
            out.append((name, "scene", name))
        elif name in curve_params:
            out.append((name, "curve", name))
        else:
            raise ValueError(f"{field}: {name!r} is not a list of distinct parameters from {known}")
    targets = [(kind, p) for _, kind, p in out]
    if not out or len(set(targets)) != len(targets):
        raise ValueError(f"{field}: {wrt!r} is not a list of distinct parameters from {known}")
    for _, kind, p in out:
        if kind == "scene" and p in ("left", "right") and getattr(scene, p) is None:
            raise ValueError(f"{field}: the scene has no {p} limiter to differentiate with respect to")
    return tuple(out)


def parameter_value(scene, target) -> float:
    """The scene's value of a resolved parameter ``(name, kind, parameter)``."""
    _, kind, p = target
    return float(scene.param_dict[p] if kind == "curve" else getattr(scene, p))


def with_parameters(scene, targets, values):
    """``scene`` with the resolved parameters ``targets`` set to ``values`` (scene numbers only: by
    ``Scene.with_numbers``, every check of the numbers; with a curve parameter: by ``replace``, every check)."""
    changes, params = {}, {}
    for (_, kind, p), v in zip(targets, values):
        (params if kind == "curve" else changes)[p] = float(v)
    if params:
        changes["params"] = params
        return scene.replace(**changes)
    return scene.with_numbers(**changes)


def _geometry(name: str):
    """The method of :class:`CurveFunctions` that evaluates the kernel ``name`` of :data:`GEOMETRY`."""
    def kernel(self, q):
        return np.asarray(getattr(self._kernels, name)(np.asarray(q, dtype=float), *self._cp), dtype=float)

    kernel.__name__ = name
    kernel.__qualname__ = f"CurveFunctions.{name}"
    kernel.__doc__ = f"The curve's ``{name}`` at ``q`` (its parameters bound; an array)."
    return kernel


class CurveFunctions:
    """The kernels of a run's curve as functions of ``q`` (NumPy arrays), its parameters bound, and the
    explicit derivatives at fixed ``q`` with respect to the resolved parameters ``targets``."""

    def __init__(self, kernels, scene, targets=(), jets=None):
        cp = tuple(scene.param_values)
        self.g, self.mu, self.m = scene.g, scene.mu, scene.m
        self.scale = float(kernels.q_scale_scalar(*cp))
        self._kernels = kernels     # (h, dh, alpha, ...: the methods of GEOMETRY read it)
        self._F = {1: kernels.F_p, -1: kernels.F_m}
        self._dF = {1: kernels.dF_p, -1: kernels.dF_m}
        self._ddF = {1: kernels.ddF_p, -1: kernels.ddF_m}
        self._N = kernels.N_w
        self._N_scalar = getattr(kernels, "N_w_scalar", None)
        self._cp = cp
        self.P = len(targets)
        self.Dmu = np.array([1.0 if t[1:] == ("scene", "mu") else 0.0 for t in targets])
        self._curve_columns = [(j, t[2]) for j, t in enumerate(targets) if t[1] == "curve"]
        self._zero_block = np.zeros((0, self.P))
        self._jets_of = jets     # a module, or a callable that loads it (only when first needed)
        self._jets = None
        #: The compiled quadratures of the run (:mod:`symvib.numeric.sensitivity_compiled`), or None: NumPy's.
        self.quadratures = None

    h, dh, alpha, dalpha, dx, dz, z, x, kappa = (_geometry(name) for name in GEOMETRY)

    @property
    def has_curve_parameters(self) -> bool:
        return bool(self._curve_columns)

    @property
    def jets(self):
        """The curve's jets module (:mod:`symvib.numeric.jet_kernels`), loaded on first use."""
        if self._jets is None:
            self._jets = self._jets_of() if callable(self._jets_of) else self._jets_of
        return self._jets

    def F(self, s, q):
        return np.asarray(self._F[s](np.asarray(q, dtype=float), self.mu, *self._cp), dtype=float)

    def f(self, s, q):
        """``F_s' = exp(2 s mu alpha) (z' + s mu x')`` (the generated ``dF`` kernel)."""
        return np.asarray(self._dF[s](np.asarray(q, dtype=float), self.mu, *self._cp), dtype=float)

    def df(self, s, q):
        """``F_s''`` (the generated ``ddF`` kernel)."""
        return np.asarray(self._ddF[s](np.asarray(q, dtype=float), self.mu, *self._cp), dtype=float)

    def df_dmu(self, s, q):
        """``d F_s' / d mu`` at fixed ``q``."""
        alpha, dx = self.alpha(q), self.dx(q)
        E = np.exp(2 * s * self.mu * alpha)
        return E * (2 * s * alpha * (self.dz(q) + s * self.mu * dx) + s * dx)

    @property
    def f_depends(self) -> bool:
        """Whether ``F_s'`` depends on a parameter of ``wrt`` at fixed ``q`` (``mu`` or the curve's)."""
        return bool(np.any(self.Dmu)) or self.has_curve_parameters

    def df_dp(self, s, q):
        """``d F_s' / d p`` at fixed ``q``, one column per parameter (shape ``(len(q), P)``)."""
        q = np.atleast_1d(np.asarray(q, dtype=float))
        out = np.zeros((len(q), self.P))
        if np.any(self.Dmu):
            out += np.outer(self.df_dmu(s, q), self.Dmu)
        for j, name in self._curve_columns:
            fn = getattr(self.jets, f"dF_{'p' if s > 0 else 'm'}_param_{self.jets.PARAM_JETS[name]}")
            out[:, j] = fn(q, self.mu, *self._cp)
        return out

    def df_dp_factors(self, s):
        """``(fn, columns)`` with ``d F_s' / d p = fn(q) * columns`` when no curve parameter is in ``wrt``
        (``fn = d F_s'/d mu``, ``columns`` the unit row of ``mu``); None otherwise.  An integral of
        ``dF_s'/dp`` is then one integral of ``fn`` times ``columns``."""
        if self._curve_columns:
            return None
        return (lambda q: self.df_dmu(s, q)), self.Dmu

    def geometry_dp(self, what, q):
        """``d(what)/dp`` at fixed ``q`` for ``what`` in :data:`symvib.codegen.jets.PARAM_JET` (``alpha``,
        ``h``, ``z``, ...), one column per parameter (shape ``(len(q), P)``; 0 but for curve parameters)."""
        q = np.atleast_1d(np.asarray(q, dtype=float))
        if not self._curve_columns:
            return self._zeros(len(q))
        out = np.zeros((len(q), self.P))
        for j, name in self._curve_columns:
            values = getattr(self.jets, f"param_jet_{self.jets.PARAM_JETS[name]}")(q, *self._cp)
            out[:, j] = values[self.jets.PARAM_JET.index(what)]
        return out

    def _zeros(self, n):
        """A read-only ``(n, P)`` block of zeros (the derivatives of the geometry without curve parameters)."""
        if self._zero_block.shape[0] < n:
            self._zero_block = np.zeros((max(n, 2 * self._zero_block.shape[0]), self.P))
            self._zero_block.setflags(write=False)
        return self._zero_block[:n]

    def dkappa(self, q) -> float:
        """``kappa'(q)`` (the jets' ``jet3``)."""
        return float(np.asarray(self.jets.jet3(np.asarray(float(q)), *self._cp)[2]))

    def N(self, q, w):
        """The normal force per unit mass at ``q`` where ``w`` is given (the scalar kernel, where the curve has one
        and it computes: ten times faster on one point than the NumPy kernel)."""
        if self._N_scalar is not None:
            try:
                return float(self._N_scalar(float(q), float(w), self.g, *self._cp))
            except (ArithmeticError, ValueError):     # (math refuses what NumPy makes NaN or inf)
                pass
        return float(self._N(float(q), float(w), self.g, *self._cp))
