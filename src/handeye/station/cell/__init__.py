"""The cell at the station: plans kept clear of it, ``handeye cell check``, the plan's preview."""
