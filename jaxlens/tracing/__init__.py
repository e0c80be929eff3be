"""The one sequential ray tracer: a surface step (intersection, refraction, validity, optical
path), traced forward from object space (``trace``, ``trace_path``) or backward from the image
side (``trace_backward``)."""

from .backward import reversed_lens as reversed_lens
from .backward import trace_backward as trace_backward
from .forward import DEFAULT_NEWTON_ITERS as DEFAULT_NEWTON_ITERS
from .forward import trace as trace
from .forward import trace_path as trace_path
