"""The basement every room stands on: the package's errors, safe files, the one YAML reader, the
extension registries, lazy exports, the write key, threads for numpy batches and time bounds.

Standard library and PyYAML only."""
