"""The contact benchmark's scene S1 in MuJoCo, for the peer column of drape's performance table.

S1 (benches/scenes/bench_s1.yaml): a 1 m square cloth of 200 g/m^2 dropped flat from z = 1.0 onto
a fixed sphere of radius 0.3 at z = 0.5, friction 0.5, 2 s simulated. MuJoCo's cloth is a 2D
flexcomp grid whose edges are equality constraints (MuJoCo's usual inextensible cloth), with
implicitfast integration and the CG solver. For each resolution and step the script prints wall
seconds per simulated second (the stepping alone), whether the state stayed finite, and how many
vertices end inside the sphere (a step too large lets the cloth through it).

    python3 -m pip install mujoco && python3 benches/peers/s1_mujoco.py [N ...]

Run it on an idle machine, in the same session as `cargo bench --bench contact`, and compare the
two as ratios.
"""

import sys
import time

import mujoco
import numpy as np

SIZE = 1.0
MASS = 0.2  # 200 g/m^2 over 1 m^2
DURATION = 2.0
STEPS = [1 / 60, 1 / 250, 1 / 500]
CENTRE = np.array([0.0, 0.0, 0.5])
RADIUS = 0.3


def model(n: int, dt: float) -> mujoco.MjModel:
    spacing = SIZE / (n - 1)
    xml = f"""
<mujoco>
  <option timestep="{dt}" solver="CG" tolerance="1e-6" integrator="implicitfast"/>
  <size memory="400M"/>
  <worldbody>
    <geom type="sphere" size="{RADIUS}" pos="0 0 0.5" friction="0.5"/>
    <flexcomp type="grid" count="{n} {n} 1" spacing="{spacing} {spacing} {spacing}"
              pos="0 0 1.0" radius="0.0025" name="cloth" dim="2" mass="{MASS}">
      <contact condim="3" friction="0.5" selfcollide="none"/>
      <edge equality="true" damping="0.001"/>
    </flexcomp>
  </worldbody>
</mujoco>"""
    return mujoco.MjModel.from_xml_string(xml)


def run(n: int, dt: float) -> str:
    m = model(n, dt)
    d = mujoco.MjData(m)
    steps = int(round(DURATION / dt))
    start = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(m, d)
    wall = time.perf_counter() - start
    x = d.flexvert_xpos
    finite = bool(np.isfinite(x).all())
    inside = int((np.linalg.norm(x - CENTRE, axis=1) < RADIUS).sum()) if finite else -1
    return f"MuJoCo {mujoco.__version__} S1 {n}x{n} | dt 1/{round(1 / dt)} | {wall / DURATION:.3f} wall s / sim s | finite {finite} | vertices inside the sphere at the end {inside}"


def main() -> None:
    sizes = [int(a) for a in sys.argv[1:]] or [32, 64]
    for n in sizes:
        for dt in STEPS:
            print(run(n, dt), flush=True)


if __name__ == "__main__":
    main()
