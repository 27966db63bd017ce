"""The wheel's build hook: the host module and the runtime's objects built
once at install time into gen/_prebuilt (gen/toolchain/prebuilt.py), so that
the first model on an empty cache compiles only itself.

A wheel gets them inside (a platform wheel); an editable install gets them in
the checkout's gen/_prebuilt (ignored by git). Without a working compiler,
or with EOMGEN_PREBUILD=0, the wheel is built without them (pure Python, as
before) and the cache builds them on first use."""
import importlib.util
import os
import shutil
import sys
import tempfile
from pathlib import Path

from hatchling.builders.hooks.plugin.interface import BuildHookInterface


class CustomBuildHook(BuildHookInterface):
    PLUGIN_NAME = "custom"

    def initialize(self, version, build_data):
        self._tmp = None
        if self.target_name != "wheel" or os.environ.get("EOMGEN_PREBUILD", "1") == "0":
            return
        # the module alone (stdlib only): importing the package would need
        # its dependencies in this process; its child process has them
        path = Path(self.root) / "gen" / "toolchain" / "prebuilt.py"
        spec = importlib.util.spec_from_file_location("_eomgen_prebuilt", path)
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        if version == "editable":
            dest = Path(self.root) / "gen" / "_prebuilt"
            shutil.rmtree(dest, ignore_errors=True)
        else:
            self._tmp = tempfile.mkdtemp(prefix="eomgen-prebuilt-")
            dest = Path(self._tmp)
        try:
            kept = mod.prebuild(dest)
        except Exception as e:  # noqa: BLE001 - the wheel still works: the cache builds them
            print(f"eomgen: the host module and runtime were not prebuilt ({e}); the first "
                  "model will build them", file=sys.stderr)
            shutil.rmtree(dest, ignore_errors=True)
            return
        if not kept:
            return
        if version != "editable":
            build_data["force_include"][str(dest)] = "gen/_prebuilt"
        build_data["pure_python"] = False
        build_data["infer_tag"] = True

    def finalize(self, version, build_data, artifact_path):
        if self._tmp:
            shutil.rmtree(self._tmp, ignore_errors=True)
