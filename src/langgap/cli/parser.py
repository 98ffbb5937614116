"""The command line's parser class: argparse's, with LangGap's one-line errors and every sub-command described."""

from __future__ import annotations

import argparse
import re
from typing import NoReturn


class Parser(argparse.ArgumentParser):
    """argparse's parser, but bad input ends as every other does: one `error:` line, exit code 2 (argparse
    prints the whole usage first)."""

    def error(self, message: str) -> NoReturn:
        if number := _NOT_A_NUMBER.fullmatch(message):
            flag, kind, value = number.groups()
            message = f"{flag} takes {_NUMBER_KINDS[kind]}, got {value}"
        self.exit(2, f"error: {self.prog}: {message} (see {self.prog} --help)\n")


# argparse's words for a flag's value that is not a number of the flag's type, said plainly.
_NOT_A_NUMBER = re.compile(r"argument (\S+): invalid (int|float) value: (.*)")
_NUMBER_KINDS = {"int": "a whole number", "float": "a number"}


def described(parser: argparse.ArgumentParser) -> None:
    """Give each sub-command's own `--help` its one-line help as its description (argparse shows it only in its
    parent's list), down every level."""
    for action in parser._actions:  # argparse lists its actions only in this private field
        if isinstance(action, argparse._SubParsersAction):
            helps = {choice.dest: choice.help for choice in action._choices_actions}
            for name, child in action.choices.items():
                child.description = child.description or helps.get(name)
                described(child)
