"""Names and defaults of a check's options that the pytest plugin shows in `pytest --help`:
they live apart from the harness (this module imports nothing) because pytest imports the
plugin in every run wherever raycheck is installed."""

# the feature families a check can run, in the order pages and grades list them
FAMILIES = ("plain", "shadows", "bounces", "shadows+bounces", "jitter", "filter",
            "jitter+filter")
DEFAULT_TIMEOUT_S = 60.0  # wall clock per render
