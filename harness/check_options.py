"""Names and defaults of a check's options that the pytest plugin shows in `pytest --help`,
and the error of a bad one: they live apart from the harness (this module imports nothing)
because pytest imports the plugin in every run wherever raycheck is installed."""

# the feature families a check can run, in the order pages and grades list them
FAMILIES = ("plain", "shadows", "bounces", "shadows+bounces", "jitter", "filter",
            "jitter+filter")
FEATURES_HELP = (f"{', '.join(FAMILIES)}; a case's own name, with the scene's bounce count "
                 "(shadows+bounces4), names its family")
DEFAULT_TIMEOUT_S = 60.0  # wall clock per render


def case_family(feature: str) -> str:
    """The family of a case's feature: every case belongs to one (cases.py makes them)."""
    family = feature_family(feature)
    if family is None:
        raise ValueError(f"the case feature {feature!r} belongs to no family")
    return family


def feature_family(name: str) -> str | None:
    """The family a feature name means: a family itself, or a case's name, whose mirror part
    carries the scene's bounce count (bounces4, shadows+bounces3), in any order of its parts;
    None for a name that is neither."""
    parts = name.strip().split("+")
    plain = ["bounces" if p.startswith("bounces") and p[len("bounces"):].isascii()
             and p[len("bounces"):].isdigit() else p
             for p in parts]
    if len(set(plain)) != len(plain):
        return None
    return next((f for f in FAMILIES if set(f.split("+")) == set(plain)), None)


class ConfigError(ValueError):
    """A bad setting of a check: the option (a CheckConfig field) and the problem."""

    def __init__(self, option: str, problem: str) -> None:
        super().__init__(f"--{option.replace('_', '-')}: {problem}")
        self.option = option
        self.problem = problem

