"""The commands, by group; each module's ``add_parsers(commands)`` registers its commands (their
options next to the handler that runs them). :func:`shimmy.cli.build_parser` calls them in the
order ``python -m shimmy --help`` lists the commands."""
