"""Record every event of the paper, catalogue and stability scenes, or compare two records.

A refactoring of the engine must leave every event as it was.  Record at two
revisions (``benchmarks/compare_revisions.py`` shows how to import another
revision) and compare::

    python benchmarks/event_snapshot.py record before.json     # at the old revision
    python benchmarks/event_snapshot.py record after.json      # at the new one
    python benchmarks/event_snapshot.py compare before.json after.json

Both backends (plain Python and numba, when installed) run each scene; the
record holds every event's kind, time, position, speeds and energy (as
``repr``, so exactly), the final state, the energy budget, the Zeno record and
a checksum of the samples.  ``compare`` prints the largest relative event
difference and every mismatch.  Works on the flat layout before issue 14 too.
"""
import json
import sys
import warnings


def record(path):
    warnings.simplefilter("ignore")
    try:
        from symvib.checks.stability import cases
        from symvib.numeric.scene import load_scene, scene_from_dict
        try:
            from symvib.api import simulate  # with the prepare step (a user curve prepared first)
        except ImportError:
            from symvib.numeric.driver import simulate
    except ImportError:
        from symvib.driver import simulate
        from symvib.scene import load_scene, scene_from_dict
        from symvib.stability import cases
    from importlib import resources

    from symvib.shapes import CATALOGUE

    scenes = {}
    for name in ("paper-parabola", "paper-cycloid", "paper-circle-3.8", "paper-circle-7"):
        with resources.as_file(resources.files("symvib") / "scenes" / f"{name}.toml") as p:
            scenes[name] = load_scene(p)
    for name, sh in CATALOGUE.items():
        for k, qdot in ((0.8, 3.0), (1.0, 1.5), (0.0, 2.0)):
            scenes[f"catalogue-{name}-k{k}-v{qdot}"] = scene_from_dict({
                "curve": {"shape": name}, "parameters": dict(sh.defaults),
                "physics": {"g": 9.81, "m": 0.2, "mu": 0.05, "restitution": k},
                "limiters": {"left": -0.5, "right": 0.5} if name != "circle" else {"left": -0.6, "right": 0.4},
                "initial": {"q": 0.1, "qdot": qdot}, "run": {"max_events": 300}})
    for c in cases():
        scenes[f"stability-{c.name}"] = c.scene
    out = {}
    for backend in ("python", "numba"):
        for name, s in scenes.items():
            try:
                r = simulate(s, backend=backend)
            except Exception as exc:  # noqa: BLE001 - recorded, so that both revisions are compared
                out[f"{backend}/{name}"] = {"error": f"{type(exc).__name__}: {exc}"}
                continue
            S = r.samples
            out[f"{backend}/{name}"] = {
                "status": r.status.value,
                "events": [(e.kind.value, *(repr(v) for v in e[1:6])) for e in r.events],
                "t_final": repr(r.t_final), "q_final": repr(r.q_final), "qdot_final": repr(r.qdot_final),
                "budget": repr(r.energy_budget), "zeno": repr(r.zeno),
                "nsamples": None if S is None else len(S.t),
                "samples_sum": None if S is None else repr(float(sum(S.t)) + float(sum(S.q))),
            }
    with open(path, "w") as f:
        json.dump(out, f, indent=0)
    print(len(out), "runs")


FIELDS = ("t_final", "q_final", "qdot_final", "budget", "zeno", "nsamples", "samples_sum")


def compare(before, after):
    with open(before) as f:
        a = json.load(f)
    with open(after) as f:
        b = json.load(f)
    worst, bad = 0.0, []
    for key in sorted(set(a) | set(b)):
        x, y = a.get(key), b.get(key)
        if x is None or y is None or "error" in x or "error" in y:
            if x != y:
                bad.append((key, x and x.get("error"), y and y.get("error")))
            continue
        if (x["status"], len(x["events"])) != (y["status"], len(y["events"])):
            bad.append((key, x["status"], y["status"], len(x["events"]), len(y["events"])))
            continue
        for ea, eb in zip(x["events"], y["events"]):
            if ea[0] != eb[0]:
                bad.append((key, "kind", ea[0], eb[0]))
                break
            for u, v in zip(map(float, ea[1:]), map(float, eb[1:])):
                if u != v:
                    worst = max(worst, abs(u - v) / max(1.0, abs(u)))
        bad.extend((key, f, x[f], y[f]) for f in FIELDS if x[f] != y[f])
    events = sum(len(v.get("events", [])) for v in a.values())
    print(f"{len(a)} runs, {events} events; largest relative event difference {worst:.1e}; mismatches {len(bad)}")
    for row in bad[:20]:
        print(row)
    return 1 if bad else 0


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "record":
        record(sys.argv[2])
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        sys.exit(compare(sys.argv[2], sys.argv[3]))
    else:
        sys.exit(__doc__)
