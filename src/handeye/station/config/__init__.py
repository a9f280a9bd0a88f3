"""The station configuration: its file, its schema, its sections and which station runs."""
