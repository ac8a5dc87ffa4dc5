"""simulate_many: wall time with 1 and 2 threads, interleaved (docs/performance.md)."""
import time, sys
sys.path.insert(0, "crates/softrod-py/tests")
import softrod
from conftest import rod
sims = [softrod.Simulation(rods=[rod(pieces=10, strains=["ky","qx","qz"], young=1e7+1e5*k)], gravity=[0,0,-9.81]) for k in range(8)]
res = {1: [], 2: []}
for rep in range(4):
    for th in (1, 2):
        t = time.perf_counter(); softrod.simulate_many(sims, 0.5, threads=th); res[th].append(time.perf_counter() - t)
for th in (1, 2):
    print(th, "threads:", " ".join(f"{x:.3f}" for x in res[th]), "min", f"{min(res[th]):.3f}")
print("speed-up (min/min):", f"{min(res[1])/min(res[2]):.2f}")
