"""The command line: ``main`` (errors to exit codes) -> ``parser`` (the grammar) -> ``commands`` (load, call the\nlibrary, hand the result to report/) with ``common`` (what every command shares);
``report_commands``: ``report`` and ``compare`` (HTML files of designs)."""
