"""The exceptions of the gradus module."""


class Error(RuntimeError):
    """An error of the renderer (image files, reconstruction inputs, ...)."""


class SceneError(Error):
    """A scene that cannot be loaded or rendered as asked.

    ``file``, ``line`` and ``column`` locate the cause where the renderer knows
    it (a scene file, an included file, ``<command line --param>`` for the
    ``params`` of a render); ``line`` and ``column`` are None otherwise.
    """

    def __init__(self, message, file=None, line=None, column=None):
        super().__init__(message)
        self.file = file
        self.line = line
        self.column = column
