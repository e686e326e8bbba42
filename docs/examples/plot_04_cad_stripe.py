"""
# A laser stripe on a CAD part

Mesh mode: the paper's seam as a CadQuery V-groove, meshed to 0.01 mm, and one stripe cast on
it with Embree (1024 rays, shadow rays to the camera, field-of-view and depth-of-field clips,
pixel quantization). The extractor's seam point is scored against the CAD edge.
"""

import matplotlib.pyplot as plt

import seamtrack as st
from seamtrack.geometry import frames
from seamtrack.sensing.sensor import preset
from seamtrack.viz.plots import draw_profile_2d

part = st.load_workpiece("v_groove", tolerance_mm=0.01, path="paper", seam_length_mm=60)
sensor = preset("paper")
above = part.seam.points[10] + [0.0, 0.0, sensor.range_center_mm]
T_world_sensor = frames.from_xyz_rpy_deg(above, [180.0, 0.0, 0.0])  # laser pointing down
profile = sensor.scan(part, T_world_sensor)
feature = st.extractor("v-groove")(profile)
distance = part.seam.closest(feature.point_world).distance_mm[0]
print(
    f"{int(profile.valid.sum())} valid points of {len(profile.valid)}; "
    f"seam point {distance:.4f} mm from the CAD seam"
)

# %%
fig, ax = plt.subplots(figsize=(8, 4), constrained_layout=True)
draw_profile_2d(ax, profile, feature=feature)
plt.show()
