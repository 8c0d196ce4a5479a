import subprocess
import sys


def test_cli_lists_serve_command():
    result = subprocess.run([sys.executable, "-m", "armlab.cli", "--help"], capture_output=True, text=True)
    assert result.returncode == 0
    assert "serve" in result.stdout


def test_cli_rejects_unknown_command():
    result = subprocess.run([sys.executable, "-m", "armlab.cli", "fly-to-the-moon"], capture_output=True, text=True)
    assert result.returncode == 2
