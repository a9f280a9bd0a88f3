"""The robot and its cell: kinematics from the robot files (``robots/*.yaml``), the cell's keep-out
volumes, clearance and self-collision of the moving arm, camera view points."""
