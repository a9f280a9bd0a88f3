"""Sub-commands of ``handeye`` (one module each; see ``src/handeye/station/cli.py``)."""
