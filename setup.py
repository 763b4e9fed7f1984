"""The Python package with the C library inside it, for pip (see pyproject.toml).

build_py builds libvoxmesh_c with CMake (Release; the tests, benchmark and CLI left out) and
puts it beside the package's modules with a _library.py naming it, so the installed package
loads its own copy. The library links what the build machine has (OpenCL's ICD loader, zlib):
a wheel made here is for machines with those packages. VOXMESH_CMAKE_ARGS adds CMake
arguments (e.g. -DVOXMESH_WITH_OPENCL=OFF); VOXMESH_BUILD_JOBS sets the parallel jobs."""

import glob
import os
import re
import shlex
import shutil
import subprocess

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.dist import Distribution

ROOT = os.path.dirname(os.path.abspath(__file__))
LIBRARY = "libvoxmesh_c.so"


def project_version():
    with open(os.path.join(ROOT, "CMakeLists.txt")) as f:
        return re.search(r"project\(voxmesh VERSION ([0-9.]+)", f.read()).group(1)


class BuildWithLibrary(build_py):
    def run(self):
        super().run()
        build = os.path.join(os.path.abspath(self.get_finalized_command("build").build_temp), "cmake")
        configure = ["cmake", "-S", ROOT, "-B", build, "-DCMAKE_BUILD_TYPE=Release", "-DVOXMESH_BUILD_TESTS=OFF",
                     "-DVOXMESH_BUILD_BENCH=OFF", "-DVOXMESH_BUILD_CLI=OFF", "-DVOXMESH_BUILD_C_API=ON"]
        if shutil.which("cmake") is None:
            raise RuntimeError("building voxmesh needs CMake and a C++20 compiler, with the OpenCL ICD loader and "
                               "zlib headers (Debian: bash scripts/install-deps.sh)")
        subprocess.check_call(configure + shlex.split(os.environ.get("VOXMESH_CMAKE_ARGS", "")))
        jobs = os.environ.get("VOXMESH_BUILD_JOBS") or str(os.cpu_count() or 1)
        subprocess.check_call(["cmake", "--build", build, "--target", "voxmesh_c", "-j", jobs])
        # The library file itself (libvoxmesh_c.so.X.Y.Z), not its links.
        built = [p for p in glob.glob(os.path.join(build, "src", "capi", LIBRARY + "*")) if not os.path.islink(p)]
        if len(built) != 1:
            raise RuntimeError(f"expected one {LIBRARY} under {build}/src/capi, found {built}")
        package = os.path.join(self.build_lib, "voxmesh")
        shutil.copyfile(built[0], os.path.join(package, LIBRARY))
        with open(os.path.join(package, "_library.py"), "w") as f:
            f.write(f'# Written by setup.py: the library pip installed with this package.\nPATH = "{LIBRARY}"\n'
                    f'VERSION = "{project_version()}"\n')


class BinaryDistribution(Distribution):
    """The wheel holds a compiled library: tagged for this platform, not pure Python."""

    def has_ext_modules(self):
        return True


# setuptools refuses an egg_base that does not exist, and a fresh checkout has none.
os.makedirs("build-python", exist_ok=True)

setup(
    version=project_version(),
    package_dir={"": "python"},
    packages=["voxmesh"],
    cmdclass={"build_py": BuildWithLibrary},
    distclass=BinaryDistribution,
    # Not build/: that is where the README's CMake build lives.
    options={"build": {"build_base": "build-python"}, "egg_info": {"egg_base": "build-python"}},
)
