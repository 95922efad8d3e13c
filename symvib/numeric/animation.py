"""An animation of a run: the particle on its curve beside its point in the phase portrait.

:func:`animate` writes a GIF (Pillow, which Matplotlib ships with) or an MP4 (when
``ffmpeg`` is on the path): on the left the curve ``x(q), z(q)`` (the generated
kernels) with its limiters and the particle at ``q(t)`` and its recent track, on
the right the run's phase portrait (:func:`symvib.numeric.figures.phase_portrait`)
with the moving state ``(q(t), qdot(t))``; a bar along the bottom shows the time.

The state between events comes from the run's dense output ``result.state(t)`` when
the result has one, otherwise from its samples (:attr:`Result.samples`: the Gauss
nodes of every motion interval, where ``q`` and ``qdot`` are exact) by cubic Hermite
interpolation in each interval (:func:`states`), which is more than a picture needs.
A run with flights (physics.md, "Flight and landing") moves the particle along its flight
arcs, the parabolas in closed form, not along the curve (:func:`positions`); its flights are
drawn dashed behind it, and the phase portrait's point waits off the axes while it flies
(it has no ``q`` in flight).

Frames are evenly spaced in time from 0 to ``t_final``: ``round(fps * duration)`` of
them (:func:`frame_times`), ``duration`` the length of the animation in seconds
(default: the run's own duration, within :data:`DEFAULT_DURATION_RANGE`).

Examples
--------
>>> from symvib.numeric.driver import simulate
>>> from symvib.numeric.scene import scene_from_dict
>>> scene = scene_from_dict({"curve": {"shape": "circle"}, "parameters": {"R": 0.5},
...     "physics": {"mu": 0.3, "restitution": 0.8}, "limiters": {"right": 0.6},
...     "initial": {"q": 0, "qdot": 5}})
>>> result = simulate(scene, backend="python")
>>> len(frame_times(result, fps=10, duration=2.0))
20
>>> q, qdot = states(result, [0.0])
>>> float(q[0]), float(qdot[0])
(0.0, 5.0)
"""
from __future__ import annotations

import numpy as np

from symvib import safeio
from symvib.numeric.events import EventKind
from symvib.paths import check_output_file

__all__ = ["animate", "check_animation_path", "frame_times", "states", "positions", "DEFAULT_FPS", "MAX_FRAMES",
           "FORMATS"]

#: Frames per second unless asked otherwise.
DEFAULT_FPS = 20
#: The default duration (s) of an animation is the run's, clipped to this range.
DEFAULT_DURATION_RANGE = (1.0, 10.0)
#: Largest number of frames (a GIF of 10 s at 60 fps); the time bar then moves at least a pixel a frame.
MAX_FRAMES = 600
#: Largest frame rate.
MAX_FPS = 60
#: Figure size (inches) and resolution: FIG_WIDTH * DPI pixels >= MAX_FRAMES, so no two frames are equal.
FIGSIZE = (10.0, 4.2)
DPI = 80
#: Share of the run shown as the particle's track behind it.
TRACK_SHARE = 0.08
#: Points of the particle's track per frame interval.
TRACK_POINTS_PER_FRAME = 8
#: Colours of a GIF frame's palette.
GIF_COLOURS = 128
#: File suffix -> Matplotlib writer name.
FORMATS = {".gif": "pillow", ".mp4": "ffmpeg"}


def frame_times(result, *, fps: float = DEFAULT_FPS, duration: float | None = None) -> np.ndarray:
    """The run times of the frames: ``round(fps * duration)`` (at least 2), evenly from 0 to ``t_final``.

    Raises
    ------
    ValueError
        For a frame rate outside ``(0, MAX_FPS]``, a duration that is not positive and
        finite, or more than :data:`MAX_FRAMES` frames (the message names the argument).
    """
    if not (isinstance(fps, (int, float)) and 0 < fps <= MAX_FPS):
        raise ValueError(f"fps: must be a number in (0, {MAX_FPS}], got {fps!r}")
    t_final = float(result.t_final)
    if duration is None:
        lo, hi = DEFAULT_DURATION_RANGE
        duration = min(max(t_final, lo), hi) if np.isfinite(t_final) else hi
    if not (isinstance(duration, (int, float)) and np.isfinite(duration) and duration > 0):
        raise ValueError(f"duration: must be a positive number of seconds, got {duration!r}")
    n = max(2, int(round(fps * duration)))
    if n > MAX_FRAMES:
        raise ValueError(f"duration: {duration:g} s at {fps:g} fps is {n} frames, more than {MAX_FRAMES}; "
                         "lower fps or duration")
    end = t_final if np.isfinite(t_final) else 0.0
    return np.linspace(0.0, end, n)


def states(result, times) -> tuple:
    """``(q, qdot)`` of a run at ``times`` (arrays; after ``t_final`` the final state).

    Uses ``result.state(t)`` where the result offers a dense output, else cubic Hermite
    interpolation of the samples in each motion interval (``q`` and ``qdot`` are exact at
    the nodes; an impact time belongs to the interval after it).
    """
    times = np.asarray(times, dtype=float)
    dense = getattr(result, "state", None)
    if callable(dense):
        try:
            out = dense(times)
            q, qdot = (out.q, out.qdot) if hasattr(out, "q") else (out[0], out[1])
            q, qdot = np.asarray(q, dtype=float), np.asarray(qdot, dtype=float)
            if q.shape == times.shape == qdot.shape:
                return q, qdot
        except Exception:  # noqa: BLE001 - an unknown dense-output interface: the samples stand in
            pass
    S = result.samples
    if S is None or len(S.t) < 2:
        return np.full(times.shape, result.q_final), np.full(times.shape, result.qdot_final)
    T, Q, V = S.t, S.q, S.qdot
    i = np.clip(np.searchsorted(T, times, side="right") - 1, 0, len(T) - 2)
    dt = T[i + 1] - T[i]
    same = (S.interval[i + 1] != S.interval[i]) | (dt <= 0)   # no interpolation across an event
    safe = np.where(same, 1.0, dt)
    x = np.clip((times - T[i]) / safe, 0.0, 1.0)
    h00, h10, h01, h11 = 2 * x**3 - 3 * x**2 + 1, x**3 - 2 * x**2 + x, -2 * x**3 + 3 * x**2, x**3 - x**2
    q = h00 * Q[i] + h10 * safe * V[i] + h01 * Q[i + 1] + h11 * safe * V[i + 1]
    qdot = ((6 * x**2 - 6 * x) * Q[i] + (3 * x**2 - 4 * x + 1) * safe * V[i] + (6 * x - 6 * x**2) * Q[i + 1]
            + (3 * x**2 - 2 * x) * safe * V[i + 1]) / safe
    q, qdot = np.where(same, Q[i], q), np.where(same, V[i], qdot)
    after = times >= result.t_final
    return np.where(after, result.q_final, q), np.where(after, result.qdot_final, qdot)


def positions(result, times) -> tuple:
    """``(x, z)`` of the particle at ``times``: on the curve at ``q(t)`` (:func:`states`), in flight on
    its parabola (the dense output's :meth:`~symvib.numeric.flight_dense.FlightDense.position`)."""
    from symvib.numeric.kernels import load

    times = np.asarray(times, dtype=float)
    q, _ = states(result, times)
    mod, cp = load(result.scene.shape), tuple(result.scene.param_values)
    on = np.isfinite(q)
    qs = np.where(on, q, 0.0)
    x = np.array(np.broadcast_to(mod.x(qs, *cp), qs.shape), dtype=float)
    z = np.array(np.broadcast_to(mod.z(qs, *cp), qs.shape), dtype=float)
    if not on.all():   # in flight: the parabola (a run with flights has its dense output)
        x[~on], z[~on] = result.dense.position(times[~on])[:2]
    return x, z


def _curve_range(result, q):
    """The ``q`` range drawn: what the run visits and its limiters, with a margin, inside the domain."""
    scene = result.scene
    marks = [v for v in (scene.left, scene.right, scene.q0, result.q_final) if v is not None]
    lo, hi = float(np.nanmin(np.r_[q, marks])), float(np.nanmax(np.r_[q, marks]))
    pad = 0.15 * max(hi - lo, 1e-3)
    return np.linspace(lo - pad, hi + pad, 400)


def check_animation_path(path, what: str = "animation file"):
    """``path`` as a :class:`~pathlib.Path` after checking, before any work, that it can be written
    (:func:`symvib.paths.check_output_file`) and that its suffix names a format this machine writes.

    >>> check_animation_path("run.avi")
    Traceback (most recent call last):
    ...
    ValueError: animation file 'run.avi': the suffix must be one of .gif, .mp4
    """
    from matplotlib import animation

    out = check_output_file(path, what)
    writer_name = FORMATS.get(out.suffix.lower())
    if writer_name is None:
        raise ValueError(f"{what} {out.name!r}: the suffix must be one of {', '.join(FORMATS)}")
    if not animation.writers.is_available(writer_name):
        raise ValueError(f"{what} {out.name!r}: {writer_name} (for {out.suffix}) is not installed here; "
                         "write a .gif instead")
    return out


def animate(result, path, *, fps: float = DEFAULT_FPS, duration: float | None = None):
    """Write the animation of ``result`` to ``path`` (``.gif``, or ``.mp4`` with ffmpeg); returns the path.

    Parameters
    ----------
    result : Result
        A run of :func:`symvib.numeric.driver.simulate` (with samples).
    path : str or path-like
        The file to write; checked before any drawing (:func:`symvib.paths.check_output_file`).
    fps : float
        Frames per second of the animation.
    duration : float, optional
        Length of the animation in seconds (default: the run's, within
        :data:`DEFAULT_DURATION_RANGE`); the run is played at ``t_final / duration``
        times real speed.

    Raises
    ------
    symvib.paths.UserPathError
        When ``path`` cannot be written.
    ValueError
        For another suffix than ``.gif``/``.mp4``, an MP4 without ffmpeg, or bad ``fps``/``duration``.
    """
    from matplotlib import animation
    from matplotlib.figure import Figure

    from symvib.numeric import figures
    from symvib.numeric.kernels import load

    out = check_animation_path(path)
    writer_name = FORMATS[out.suffix.lower()]
    times = frame_times(result, fps=fps, duration=duration)
    q, qdot = states(result, times)
    scene = result.scene
    mod, cp = load(scene.shape), tuple(scene.param_values)

    fig = Figure(figsize=FIGSIZE, dpi=DPI)
    ax_curve, ax_phase = fig.subplots(1, 2)
    arc = _curve_range(result, q)
    ax_curve.plot(mod.x(arc, *cp), mod.z(arc, *cp), color="0.4", lw=1.5)
    for side in ("left", "right"):
        lim = getattr(scene, side)
        if lim is not None:
            ax_curve.plot(mod.x(lim, *cp), mod.z(lim, *cp), "s", color="tab:red", ms=8)
    ax_curve.set_aspect("equal", adjustable="datalim")
    ax_curve.set_xlabel("$x$ [m]")
    ax_curve.set_ylabel("$z$ [m]")
    ax_curve.grid(alpha=0.3)
    flying = bool(result.count(EventKind.LIFT_OFF))
    ax_curve.set_title(f"{scene.shape.name}: the particle on the curve{' and in flight' * flying}", fontsize=10)
    figures.phase_portrait(result, ax=ax_phase)
    xs, zs = positions(result, times)
    fine = np.linspace(0.0, times[-1], TRACK_POINTS_PER_FRAME * len(times))
    fine_x, fine_z = positions(result, fine)
    for x_arc, z_arc in figures.flight_arcs(result):   # the flights, behind the particle
        ax_curve.plot(x_arc, z_arc, **figures.FLIGHT_STYLE, alpha=0.5)
    (track,) = ax_curve.plot([], [], color="tab:orange", lw=2, alpha=0.6)
    (particle,) = ax_curve.plot([], [], "o", color="tab:orange", ms=10, mec="k")
    (state,) = ax_phase.plot([], [], "o", color="tab:orange", ms=9, mec="k", zorder=5)
    clock = fig.text(0.01, 0.02, "", fontsize=9)
    bar = fig.add_artist(_bar())
    moving = (track, particle, state, clock, bar)
    impacts = np.array([e.t for e in result.events if e.kind is EventKind.IMPACT])
    landings = np.array([e.t for e in result.events if e.kind is EventKind.LANDING])
    t_end = times[-1] if times[-1] > 0 else 1.0
    behind = TRACK_SHARE * t_end

    def draw(k):
        t = times[k]
        recent = (fine >= t - behind) & (fine <= t)
        track.set_data(np.r_[fine_x[recent], xs[k]], np.r_[fine_z[recent], zs[k]])
        particle.set_data([xs[k]], [zs[k]])
        state.set_data([q[k]], [qdot[k]])
        n_imp = int(np.sum(impacts <= t))
        text = f"t = {t:.3f} s of {result.t_final:.3f} s, {n_imp} impact{'s' * (n_imp != 1)}"
        if flying:
            n_land = int(np.sum(landings <= t))
            text += f", {n_land} landing{'s' * (n_land != 1)}"
        clock.set_text(text)
        bar.set_width(t / t_end)
        return moving

    fig.tight_layout(rect=(0, 0.05, 1, 1))
    # Written whole under a temporary name created here, then renamed onto ``out`` (never through a link).
    with safeio.replacing_file(out, what="animation file") as fh:
        if writer_name == "pillow":
            _write_gif(fig, moving, draw, len(times), fh, fps)
        else:  # pragma: no cover - needs ffmpeg
            movie = animation.FuncAnimation(fig, draw, frames=len(times), blit=False)
            movie.save(fh.temporary, writer=animation.writers[writer_name](fps=fps), dpi=DPI)
    return out


def _write_gif(fig, moving, draw, n_frames, out, fps):
    """Draw the still parts once, then only the moving artists on a copy of them (blitting); Pillow writes."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    canvas = FigureCanvasAgg(fig)
    for artist in moving:
        artist.set_animated(True)
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)
    size = canvas.get_width_height()
    frames = []
    for k in range(n_frames):
        draw(k)
        canvas.restore_region(background)
        for artist in moving:
            fig.draw_artist(artist)
        frames.append(Image.frombuffer("RGBA", size, bytes(canvas.buffer_rgba()), "raw", "RGBA", 0, 1)
                      .convert("RGB").quantize(colors=GIF_COLOURS))
    frames[0].save(out, format="GIF", save_all=True, append_images=frames[1:], duration=round(1000 / fps), loop=0)


def _bar():
    """The time bar: a thin rectangle along the bottom of the figure, its width the share of time gone."""
    from matplotlib.patches import Rectangle

    return Rectangle((0.0, 0.0), 0.0, 0.012, color="tab:orange")
