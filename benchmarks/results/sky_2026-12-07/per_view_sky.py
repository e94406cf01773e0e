import pickle, time, sys, numpy as np
from morphosim_gym.render.cpu.sky import composite_sky_compiled as f
import morphosim_gym; print(morphosim_gym.__file__, file=sys.stderr)
cases = pickle.load(open('/tmp/sky/cases.pkl', 'rb'))
for c in cases: f(*c)
ts = []
for _ in range(7):
    t0 = time.perf_counter()
    for _ in range(100):
        for c in cases: f(*c)
    ts.append((time.perf_counter() - t0) / (100 * len(cases)) * 1e6)
print(f"{np.median(ts):.1f} us/view", "uncovered mean", np.mean([(c[1] < 0.999).sum() for c in cases]))
