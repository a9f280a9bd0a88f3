"""The operator-guided capture: jogged by the operator, or by the guided RAPID program."""
