"""The station's checkerboard, the one default of every board setting (no import beyond the standard
library, so the command line can show it without loading numpy): 13 x 8 inner corners (14 x 9
squares) of 30 mm. ``compact_points.STATION_BOARD`` is the same as a ``BoardGeometry``."""

__all__ = ["STATION_CORNERS", "STATION_SQUARE_MM"]

#: Inner corners along x (the long side), along y.
STATION_CORNERS = (13, 8)
#: Square size, mm.
STATION_SQUARE_MM = 30.0
