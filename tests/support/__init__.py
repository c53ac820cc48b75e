"""Dev-only helpers the tests and benchmarks share (not shipped: ``nodes`` never imports them). Tests find this
package through pytest's ``pythonpath = ["tests"]``; benchmarks put ``tests/`` on ``sys.path`` themselves."""
