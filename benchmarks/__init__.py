"""jaxlens benchmark suite: ``python -m benchmarks [--smoke | --full]`` (see ``run.py``)."""
