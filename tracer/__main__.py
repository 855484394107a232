"""`python -m raycheck.tracer`: the tracer's command line (cli.py), in a process that only
renders."""
from .kernel.backend import begin_render_process, end_render_process
from .process import interruptible

begin_render_process()  # before the tracer imports numpy


def _main() -> int:
    from .cli import main

    return main()


end_render_process(interruptible("python -m raycheck.tracer", _main, ending=True))
