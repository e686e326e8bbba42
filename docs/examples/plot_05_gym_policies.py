"""
# A PD policy and a random one in the Gymnasium environment

``import seamtrack.gym`` registers ``seamtrack/Scene-v0``: one step is one sensor frame, the
observation the stripe profile plus the torch's state, the action a lateral and vertical
correction in mm ([The Gymnasium environment](../../gym.md)). Nothing is trained here: a PD law
on the groove's root seen in the profile (:class:`seamtrack.gym.ProfilePD`), zero action (the
torch follows the straight line between the seam's ends) and random corrections, side by side
on the first 100 mm of ``paper-v-groove`` (at 10 mm/s, 256 rays: about a thousand frames).
"""

import gymnasium
import matplotlib.pyplot as plt
import numpy as np

import seamtrack.gym as sgym

env = gymnasium.make(
    "seamtrack/Scene-v0",
    scene="paper-v-groove",
    overrides={
        "workpiece.params.seam_length_mm": 100.0,
        "simulation.welding_speed_mm_s": 10.0,
        "sensor.rays": 256,
    },
)
env.action_space.seed(0)
policies = {
    "PD on the profile": sgym.ProfilePD(env),
    "zero action (the nominal line)": lambda obs: np.zeros(2, dtype=np.float32),
    "random": lambda obs: env.action_space.sample(),
}
runs = {}
for name, policy in policies.items():
    obs, info = env.reset(seed=0)
    if hasattr(policy, "reset"):
        policy.reset()
    t, error, total = [info["t_s"]], [info["error_mm"]], 0.0
    while True:
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        total += reward
        if "error_mm" in info:
            t.append(info["t_s"])
            error.append(info["error_mm"])
        if terminated or truncated:
            break
    runs[name] = (np.array(t), np.array(error))
    print(
        f"{name:32s} {len(t) - 1:5d} steps, return {total:10.1f}, mean error "
        f"{np.mean(error):.3f} mm, max {np.max(error):.3f} mm, ends: {info['status']}"
    )
env.close()

# %%
# The random policy's corrections add up to a random walk: it loses the seam (farther than
# half the sensor's near field of view from it) within a few seconds, and the loss penalty
# (``lost_mm`` for every frame left to the seam's end) dominates its return. Zero action keeps
# to the straight line, up to 2.9 mm off the curving seam; the PD law follows the curve.
fig, ax = plt.subplots(figsize=(8, 4), constrained_layout=True)
for name, (t, error) in runs.items():
    ax.plot(t, error, label=name)
ax.set_xlabel("time (s)")
ax.set_ylabel("torch tip to seam (mm)")
ax.set_yscale("log")
ax.legend()
plt.show()
