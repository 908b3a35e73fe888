"""The command line explains itself: every option and positional has a help text, every command
an examples epilog, and each example parses with the real parser (so an example cannot name an
option that does not exist)."""
import argparse
import shlex

import pytest

from taichi_dem.app import cli


def _commands():
    parser = cli._parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return parser, sub.choices


def test_every_option_has_help():
    parser, commands = _commands()
    missing = [f"taichi-dem {name} {a.dest}" for name, command in commands.items()
               for a in command._actions if not a.help and a.dest != "help"]
    missing += [a.dest for a in parser._actions if not a.help and a.dest != "help"]
    assert missing == []


def test_every_command_has_examples():
    parser, commands = _commands()
    assert set(cli.EXAMPLES) == set(commands)
    assert "examples:" in parser.format_help()
    for name, command in commands.items():
        assert "examples:" in command.format_help(), name


@pytest.mark.parametrize("example", [e for lines in cli.EXAMPLES.values() for e in lines])
def test_examples_parse(example):
    words = shlex.split(example, comments=True)
    for operator in ("|", ">"):                       # a shell pipe or redirection ends the command
        words = words[:words.index(operator)] if operator in words else words
    assert words[0] == "taichi-dem"
    args = cli._parser().parse_args(words[1:])     # argparse exits (SystemExit) on a bad example
    assert args.command == words[1]
