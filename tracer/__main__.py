from .backend import begin_render_process, end_render_process

begin_render_process()  # before the tracer imports numpy

from .cli import main  # noqa: E402

end_render_process(main())
