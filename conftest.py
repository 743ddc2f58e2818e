# Makes the source tree importable for the tests (pytest puts this folder on sys.path).
