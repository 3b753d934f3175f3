"""Only what pyproject.toml cannot say: put ``sb3_smc_gym_hook.pth`` at the root of the wheel (site-packages), in
the editable wheel of ``pip install -e .`` too.

See ``_sb3_smc_gym_hook.py``: it registers the ``PW-*`` ids when Gymnasium is imported.
"""

from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

HOOK = "sb3_smc_gym_hook.pth"


class BuildWithHook(build_py):
    def run(self) -> None:
        super().run()
        self.copy_file(str(Path(__file__).parent / HOOK), str(Path(self.build_lib) / HOOK))
        if self.editable_mode:
            # an editable wheel carries no build_lib file; setuptools writes the wheel's non-editable files (the
            # install command's folders) straight into the unpacked wheel, whose root is site-packages
            install_lib = self.get_finalized_command("install").install_lib
            self.copy_file(str(Path(__file__).parent / HOOK), str(Path(install_lib) / HOOK))

    def get_outputs(self, include_bytecode: bool = True) -> list[str]:
        return [*super().get_outputs(include_bytecode), str(Path(self.build_lib) / HOOK)]


setup(cmdclass={"build_py": BuildWithHook})
