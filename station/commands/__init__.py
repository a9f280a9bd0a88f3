"""Sub-commands of ``handeye`` (one module each; see ``station/cli.py``)."""
