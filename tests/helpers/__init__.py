"""Helpers shared by the tests: hand-made data, tiny models, a local HTTP server, the real
data's location. Test modules import from here (``from helpers.data import shared_file``;
pytest puts ``tests/`` on ``sys.path``), never from one another."""
