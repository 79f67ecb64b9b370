"""Build hook: ship the top-level ``models/`` tree inside the wheel as ``drakedeburr/models``.

Everything else is declared in pyproject.toml. ``drakedeburr.resources`` looks for the models
next to the installed package first and in the source checkout second.
"""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py


class BuildPyWithModels(build_py):
    def run(self) -> None:
        super().run()
        src = Path(__file__).resolve().parent / "models"
        dst = Path(self.build_lib) / "drakedeburr" / "models"
        if src.is_dir():
            if dst.exists():
                shutil.rmtree(dst)
            shutil.copytree(src, dst, ignore=shutil.ignore_patterns("__pycache__"))


setup(cmdclass={"build_py": BuildPyWithModels})
