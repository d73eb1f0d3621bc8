"""Marks the wheel as platform-specific: it carries the prebuilt extension module (see pyproject.toml)."""
from setuptools import setup
from setuptools.dist import Distribution


class PrebuiltExtension(Distribution):
    def has_ext_modules(self):
        return True


setup(distclass=PrebuiltExtension)
