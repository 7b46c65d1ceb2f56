"""Subcommands of the ``ibr`` command line (see ``cli.py``).

Each module defines ``HELP`` (one line), ``add_arguments(parser)`` and ``run(args) -> int``.
Modules import the library lazily inside ``run`` so that ``ibr --help`` stays fast. No
algorithm lives here: parse, call the library, report, exit.
"""
