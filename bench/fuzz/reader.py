"""atheris on the recording reader: ``load_recording`` fed arbitrary bytes as every file kind
(text, compressed, zipped, npz, HDF5, UFF; :mod:`targets`). The property: a valid recording
or one ``RecordingError`` with a one-line message; any other exception, a crash, a hang
(``-timeout``) or a memory blow-up (``-rss_limit_mb``) is a finding, written to
``build/fuzz/reader-crash-*`` and replayed with ``python bench/fuzz/reader.py FILE``.

    pip install atheris        # Linux and macOS, CPython 3.11-3.13
    python bench/fuzz/reader.py -max_total_time=3600 -timeout=20
"""

import atheris

with atheris.instrument_imports(include=["algid", "targets"]):
    import targets

if __name__ == "__main__":
    targets.fuzz("reader", targets.reader)
