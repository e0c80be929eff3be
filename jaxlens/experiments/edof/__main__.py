"""``python -m jaxlens.experiments.edof``: the EDoF experiment's command line (see ``cli``)."""

from .cli import main

main()
