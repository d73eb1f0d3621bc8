"""The README's install path works: scripts/install_python.sh builds a wheel offline and installs it into
a virtual environment on Debian's python3, where `import clutterseg` finds the installed package (not the
build folder) and segments a frame."""
import os
import subprocess

from conftest import SOURCE_DIR


def test_install_script_makes_an_importable_package(tmp_path):
    venv = tmp_path / "venv"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}  # nothing but the install may be found
    subprocess.run(["bash", str(SOURCE_DIR / "scripts" / "install_python.sh"), str(venv)], check=True, env=env,
                   timeout=240, capture_output=True)
    probe = (
        "import clutterseg, numpy\n"
        "print(clutterseg.__file__)\n"
        f"frame = clutterseg.Dataset({str(SOURCE_DIR / 'examples' / 'osd-test50')!r})['test50']\n"
        "result = clutterseg.Segmenter().segment(frame.depth, frame.camera)\n"
        "print(len(result.objects), int(result.object_labels.max()))\n"
    )
    run = subprocess.run([str(venv / "bin" / "python3"), "-c", probe], env=env, cwd=tmp_path, timeout=120,
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    location, counts = run.stdout.splitlines()
    assert location.startswith(str(venv / "lib")), location
    objects, max_label = map(int, counts.split())
    assert objects == max_label > 1
