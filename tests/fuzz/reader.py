"""atheris on the recording reader: ``load_recording`` fed arbitrary bytes as every file kind
(text, compressed, zipped, npz, HDF5, UFF; :mod:`targets`). The property: a valid recording
or one ``RecordingError`` with a one-line message; any other exception, a crash, a hang
(``-timeout``) or a memory blow-up (``-rss_limit_mb``) is a finding, written to
``build/fuzz/reader-crash-*`` and replayed with ``python tests/fuzz/reader.py FILE``.

It measures nothing: it searches for inputs that break the property. The default stops after
2 minutes of fuzzing (``targets.DEFAULT_SECONDS``), or earlier at a finding; an input that runs
longer than 20 s is one (``-timeout=20`` unless given); the published hour (docs/reliability.md,
"Coverage-guided fuzzing") is the second command below:

    pip install atheris        # Linux and macOS, CPython 3.11-3.13
    python tests/fuzz/reader.py                       # 2 minutes
    python tests/fuzz/reader.py -fork=1 -ignore_timeouts=1 -ignore_ooms=1 -max_total_time=3600 \
        -timeout=20 -rss_limit_mb=3000
"""

import atheris

with atheris.instrument_imports(include=["algid", "targets"]):
    import targets

if __name__ == "__main__":
    targets.fuzz("reader", targets.reader, timeout=20)
