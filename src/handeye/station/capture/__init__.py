"""The planned capture: the plan, the visiting loop and what it tells an observer."""
