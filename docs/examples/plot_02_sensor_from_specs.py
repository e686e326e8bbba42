"""
# A sensor from its data sheet

`LaserLineSensor.from_specs` solves the triangulation geometry (baseline, laser angle, chip)
from a data sheet's depth of field, near and far field of view and resolutions; the paper's
Eq. 4-8 give the specs back. The resolution the paper quotes is an average: one pixel's step
in range grows from the near end of the range to the far end.
"""

import matplotlib.pyplot as plt
import numpy as np

import seamtrack as st

sensor = st.LaserLineSensor.from_specs(
    depth_of_field_mm=60,
    fov_near_mm=18,
    fov_far_mm=32,
    angle_deg=16.17,
    depth_resolution_mm=0.01,
    lateral_resolution_mm=0.01,
)
print(
    f"baseline b = {sensor.baseline_mm:.2f} mm, depth of field {sensor.depth_of_field_mm:.3f} mm, "
    f"field {sensor.fov_near_mm:.3f} to {sensor.fov_far_mm:.3f} mm"
)

# %%
# A point of the laser plane to the chip and back (Eq. 1-3), then the local depth resolution.
x_c, z_c = sensor.project([0.0, 5.0], [90.0, 100.0])
print("back to the laser plane:", np.round(sensor.triangulate(x_c, z_c), 9))

z = np.linspace(sensor.range_near_mm, sensor.range_far_mm, 200)
fig, ax = plt.subplots(figsize=(7, 3.5), constrained_layout=True)
ax.plot(z, sensor.local_depth_resolution_mm(z))
ax.axhline(0.01, color="0.6", ls="--", label="Table 3: 0.01 mm (average)")
ax.set_xlabel("range z_L (mm)")
ax.set_ylabel("one pixel's step in range (mm)")
ax.legend()
plt.show()
