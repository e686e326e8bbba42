"""
# The moving arc's temperature (Rosenthal)

Isotherms of one MAG arc (0.8 x 20 V x 120 A = 1920 W at 6 mm/s, 320 J/mm) on carbon steel: the thick
plate's point source, the thin plate's line source (3 mm) and the image sources of a 3 mm and a
10 mm plate, on the top face in the arc's frame (x along the travel, the arc at the origin).
The 3 mm plate's images and its line source draw the same isotherms away from the arc; the
10 mm plate lies between the thin and the thick plate. The 1500 degC isotherm is about
where carbon steel melts: Rosenthal's field says nothing inside it.
"""

import matplotlib.pyplot as plt
import numpy as np

import seamtrack as st
from seamtrack.heat.materials import THERMAL_MATERIALS

steel = THERMAL_MATERIALS["carbon_steel"]
kw = dict(
    power_w=0.8 * 20.0 * 120.0,
    speed_mm_s=6.0,
    conductivity_w_per_mm_k=steel.conductivity_w_per_mm_k,
    diffusivity_mm2_per_s=steel.diffusivity_mm2_per_s,
)
x, y = np.meshgrid(np.linspace(-60.0, 15.0, 301), np.linspace(-20.0, 20.0, 161))
x, y = x + 0.0625, y + 0.0625  # off the source itself, where the field is infinite
top = np.stack([x, y, np.zeros_like(x)], axis=-1)
fields = {
    "thick plate (point source)": st.rosenthal_temperature(top, **kw),
    "3 mm, line source": st.rosenthal_temperature(top, thickness_mm=3.0, **kw),
    "3 mm, image sources": st.image_source_temperature(top, thickness_mm=3.0, **kw),
    "10 mm, image sources": st.image_source_temperature(top, thickness_mm=10.0, **kw),
}
levels = [200, 400, 600, 800, 1000, 1500]
fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True, constrained_layout=True)
for ax, (name, t) in zip(axes, fields.items(), strict=True):
    cs = ax.contour(x, y, t, levels=levels, cmap="inferno")
    ax.clabel(cs, fmt="%d")
    ax.set_title(name)
    ax.set_aspect("equal")
    ax.set_ylabel("y (mm)")
axes[-1].set_xlabel("x along the travel (mm)")
plt.show()

# %%
# Through the 10 mm plate, across the weld at the arc (x = -2 mm): the top is hotter than the
# bottom, which bends the plate away from the torch while it lasts
# (`seamtrack.heat.distortion.transient_angle_rad`).
yy, zz = np.meshgrid(np.linspace(-20.0, 20.0, 161), np.linspace(0.0, 10.0, 41))
section = np.stack([np.full_like(yy, -2.0), yy, zz], axis=-1)
t = st.image_source_temperature(section, thickness_mm=10.0, **kw)
fig, ax = plt.subplots(figsize=(8, 3), constrained_layout=True)
cs = ax.contour(yy, zz, t, levels=levels, cmap="inferno")
ax.clabel(cs, fmt="%d")
ax.invert_yaxis()
ax.set_xlabel("y across the weld (mm)")
ax.set_ylabel("depth z (mm)")
ax.set_aspect("equal")
plt.show()
