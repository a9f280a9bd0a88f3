"""``handeye verify``: the check of a calibration, its plan, outcome, history and quick update."""
