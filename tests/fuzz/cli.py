"""atheris on the command line: ``algid identify FILE`` and ``algid diagnose FILE`` run in this
process on arbitrary files (:mod:`targets`; the input's first byte after the file kind's
picks the command). The property: exit 0, 2 or 3, and an exit 2 says why in one line of at
most 200 characters; an exception the command does not turn into its exit code (the catch-all
of ``algid.cli.main`` is bypassed to see it), a crash or a hang is a finding, written to
``build/fuzz/cli-crash-*``.

It measures nothing: it searches for inputs that break the property. The default stops after
2 minutes of fuzzing (``targets.DEFAULT_SECONDS``), or earlier at a finding; an input that runs
longer than 60 s is one (``-timeout=60`` unless given); the published hour (docs/reliability.md,
"Coverage-guided fuzzing") is the second command below:

    python tests/fuzz/cli.py                          # 2 minutes
    python tests/fuzz/cli.py -fork=1 -ignore_timeouts=1 -ignore_ooms=1 -max_total_time=3600 \
        -timeout=60 -rss_limit_mb=3000
"""

import atheris

with atheris.instrument_imports(include=["algid", "targets"]):
    import targets

    import algid.diagnosis.engine  # noqa: F401 - instrumented before the commands import them
    import algid.identification.engine  # noqa: F401


def one_input(data: bytes, folder) -> int:
    name = "diagnose" if len(data) > 1 and data[1] & 2 else "identify"
    return targets.command(data, folder, name)


if __name__ == "__main__":
    targets.fuzz("cli", one_input, timeout=60)
