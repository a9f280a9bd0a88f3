"""What the station says about one calibration: the assessment, the verdict and its presenters."""
