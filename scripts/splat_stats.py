"""`python3 scripts/splat_stats.py FILE.ply ...` (docs/performance.md, "Trained-scene statistics"):
Statistics of 3DGS PLY files: log-scales per axis, smallest/largest axis ratio, sigmoid
opacities, DC colours, and how clustered the centres are (nearest-neighbour distance against a
uniform cube of the same bounding box)."""
import math, struct, sys, random

def read(path):
    with open(path, 'rb') as f:
        props, n = [], 0
        assert f.readline().strip() == b'ply'
        while True:
            line = f.readline().strip().decode()
            if line.startswith('element vertex'): n = int(line.split()[2])
            elif line.startswith('property'): props.append(line.split()[2])
            elif line == 'end_header': break
        rec = struct.Struct('<' + 'f' * len(props))
        data = f.read(rec.size * n)
    rows = [dict(zip(props, rec.unpack_from(data, i * rec.size))) for i in range(n)]
    return rows

def q(v, ps=(0.01, 0.1, 0.25, 0.5, 0.75, 0.9, 0.99)):
    v = sorted(v); return ' '.join(f'{v[min(len(v)-1, int(p*len(v)))]:.3g}' for p in ps)

def nn_median(pts, m=400, seed=1):
    r = random.Random(seed); sample = r.sample(pts, min(m, len(pts)))
    ds = []
    for a in sample:
        best = min(((a[0]-b[0])**2+(a[1]-b[1])**2+(a[2]-b[2])**2) for b in pts if b is not a)
        ds.append(math.sqrt(best))
    ds.sort(); return ds[len(ds)//2]

for path in sys.argv[1:]:
    rows = read(path); n = len(rows)
    print(f'== {path.split("/")[-1]}: {n} Gaussians')
    s = [[r[f'scale_{i}'] for i in range(3)] for r in rows]
    for i in range(3): print(f'  scale_{i} (ln σ) quantiles 1/10/25/50/75/90/99 %: {q([x[i] for x in s])}')
    ss = [sorted(x) for x in s]
    print(f'  ln s_max: {q([x[2] for x in ss])}')
    print(f'  ln s_min: {q([x[0] for x in ss])}')
    print(f'  ln s_mid - ln s_min: {q([x[1]-x[0] for x in ss])}')
    print(f'  s_min/s_max: {q([math.exp(x[0]-x[2]) for x in ss])}')
    op = [1/(1+math.exp(-r['opacity'])) if r['opacity'] > -700 else 0.0 for r in rows]
    print(f'  opacity: {q(op)}; <0.05: {sum(o<0.05 for o in op)/n:.3f}, >0.95: {sum(o>0.95 for o in op)/n:.3f}')
    C0 = 0.28209479177387814
    for c in range(3): print(f'  colour {c}: {q([max(0, 0.5 + C0*r[f"f_dc_{c}"]) for r in rows])}')
    pts = [(r['x'], r['y'], r['z']) for r in rows]
    lo = [min(p[i] for p in pts) for i in range(3)]; hi = [max(p[i] for p in pts) for i in range(3)]
    ext = [h-l for l, h in zip(lo, hi)]
    rr = random.Random(2)
    uni = [tuple(lo[i] + rr.random()*ext[i] for i in range(3)) for _ in range(n)]
    a, b = nn_median(pts), nn_median(uni)
    med_smax = sorted(math.exp(x[2]) for x in ss)[n//2]
    print(f'  bbox extent {ext[0]:.3g} {ext[1]:.3g} {ext[2]:.3g}; median nearest-neighbour {a:.3g} against {b:.3g} uniform (ratio {a/b:.3f}); median s_max {med_smax:.3g}')
