"""The environment of a new user's first run, for tests that must not lean on this session's
caches or settings."""
from __future__ import annotations

import os
from pathlib import Path


def cold_env(home: Path) -> dict[str, str]:
    """A new user's environment: HOME empty (no Dr.Jit kernel cache, no raycheck cache), no
    settings of this test session's."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("RAYCHECK_", "DRJIT_CACHE"))}
    home.mkdir(parents=True, exist_ok=True)
    return dict(env, HOME=str(home), PYTHONUNBUFFERED="1")
