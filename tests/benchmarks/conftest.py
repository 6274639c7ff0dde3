"""The benchmarks share the caustics-mapping tests' context fixtures."""

from tests.renderers.caustics_mapping.conftest import context_factory, ctx  # noqa: F401
