"""The one error type for bad user input, shared by every stage."""


class InputError(ValueError):
    """Bad input the user can fix. The message is one line: what is wrong and how to fix it.

    `pipeline.py` prints it as `error: <message>` and exits with code 2, without a traceback.
    """
