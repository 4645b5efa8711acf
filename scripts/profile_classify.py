"""CPU of each stage of classify for one catalogue entry (docs/diagnostics.md, §8): one JSON line per
stage — degrees over F_p (20 steps), exact degrees over Q (6 iterates), the integral search at
classify's defaults, the measure search, the Poisson search.  Run each entry in its own process,
with a time limit, e.g.

    for n in $(exact-khk systems --json | python -c "import json,sys; print(*[s['name'] for s in json.load(sys.stdin)['systems']])"); do
      for s in degrees exact integrals measure poisson; do timeout 90 python scripts/profile_classify.py $n $s; done
    done
"""
import json
import resource
import sys
import time

from exact_khk.diagnostics.classify import default_degree, default_fit_degree
from exact_khk.diagnostics.degrees import degree_sequence, eps_of, exact_degrees, resolve_field

name, stage = sys.argv[1], sys.argv[2]
steps = int(sys.argv[3]) if len(sys.argv) > 3 else 20
sysobj, fld = resolve_field(name, "f")
eps = eps_of(sysobj, None)
c0, t0 = resource.getrusage(resource.RUSAGE_SELF).ru_utime, time.perf_counter()
if stage == "degrees":
    d = degree_sequence(sysobj, steps=steps, eps=eps)
    info = f"{list(d.degrees)} {d.fit.growth}"
elif stage == "exact":
    info = str(exact_degrees(fld, eps, 6, 10_000))
elif stage == "integrals":
    from exact_khk.diagnostics.integrals import find_integrals
    deg = default_degree(fld.dim)
    r = find_integrals(sysobj, degree=deg, eps=eps, fit_degree=default_fit_degree(fld.dim, deg))
    info = f"degree {deg}: {len(r.integrals)} found, {r.independent} independent"
elif stage == "measure":
    from exact_khk.diagnostics.measures import find_measure
    info = f"{len(find_measure(sysobj, eps=eps).densities)} densities"
elif stage == "poisson":
    from exact_khk.diagnostics.poisson import find_poisson
    info = f"{len(find_poisson(sysobj, eps=eps).tensors)} tensors"
else:
    sys.exit(f"unknown stage {stage!r}: degrees, exact, integrals, measure or poisson")
print(json.dumps({"name": name, "stage": stage, "cpu": round(resource.getrusage(resource.RUSAGE_SELF).ru_utime - c0, 2),
                  "wall": round(time.perf_counter() - t0, 2), "info": info}))
