"""Errors that lumos reports to its users.

`LumosError` is bad input: a scene file, an argument or a path the user gave. Its message is one line that
names the file, the key path or line number, and what is wrong. The CLI prints it and exits with code 2;
anything else that escapes is an internal error (exit code 1).
"""


class LumosError(Exception):
    """Bad input from the user (scene, arguments, files). The message is one line."""


class SceneError(LumosError):
    """A scene file or dict that does not describe a valid scene."""


class LumosWarning(UserWarning):
    """Input that lumos can render but changes: a material that would create energy, a setting it ignores.
    The CLI prints each as one line `lumos: warning: <message>` on stderr."""
