"""Camera twin constants that the plugin module needs without importing numpy."""

TABLE_MM = (743.46, 447.29)  # 3M SCT-3250 active glass, paper section 2
IMAGE_PX = (640, 480)  # PS3 Eye, paper section 2

#: Undistorted pixel positions of the glass corners (0,0), (W,0), (W,H), (0,H):
#: about 0.82 px/mm, with a little keystone. Seen from below, so mirrored: table x runs
#: right-to-left and table y bottom-to-top in the image (x left, y up is a reflection).
DEFAULT_CORNERS_PX = ((627.0, 429.0), (13.0, 421.0), (21.0, 52.0), (617.0, 57.0))
