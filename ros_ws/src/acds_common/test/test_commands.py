"""Typed ground commands and the mode report: one parser per command, one layout of the ``mode`` status."""

from __future__ import annotations

import pytest
from acds_common.cdr import Status
from acds_common.commands import (
    CommandError,
    EeaSelect,
    GainCommand,
    GasCommand,
    LawCommand,
    MagnetometerSelect,
    ModeCommand,
    decode,
)
from acds_common.messages import MODE_STATUS, OK
from acds_common.mode_report import ModeReport, ModeStatusReader, mode_state, mode_status, run_complete

GROUND = (ModeCommand, EeaSelect, MagnetometerSelect, LawCommand, GainCommand, GasCommand)


@pytest.mark.parametrize(('text', 'command', 'normalised'), [
    ('MODE Celestial_Point', ModeCommand('celestial_point'), 'mode celestial_point'),
    ('eea_select Y b', EeaSelect(1, 'B'), 'eea_select y B'),
    ('magnetometer_select a', MagnetometerSelect('A'), 'magnetometer_select A'),
    ('law Unloading LEAD', LawCommand('unloading', 'lead'), 'law unloading lead'),
    ('gain Max_Moment 1.5e3', GainCommand('max_moment', 1500.0), 'gain max_moment 1500.0'),
    ('gas isolation 2 OPEN', GasCommand('isolation', True, 2), 'isolation 2 open'),
    ('gas bank off', GasCommand('bank', False), 'bank off'),
])
def test_each_command_parses_to_its_object_and_its_text_is_the_normalised_command(text, command, normalised):
    assert decode(text, GROUND) == command
    assert command.text == normalised
    forwarded = normalised.split()
    family = type(command)
    assert (family.parse(forwarded) if family is GasCommand else family.parse(forwarded[1:])) == command


@pytest.mark.parametrize(('text', 'reason'), [
    ('', 'empty command'), ('warp 9', "unknown command 'warp'; known: mode, eea_select"),
    ('mode', 'usage: mode <name>'), ('eea_select w A', 'usage: eea_select'), ('magnetometer_select C', 'usage'),
    ('law unloading', 'usage: law'), ('gain max_moment x', "gain value 'x' is not a number"),
    ('gain max_moment nan', 'not finite'), ('gas isolation 3 open', 'usage: gas isolation'),
    ('gas bank maybe', 'usage: gas'),
])
def test_a_text_that_does_not_parse_is_refused_with_the_reason(text, reason):
    with pytest.raises(CommandError, match=reason):
        decode(text, GROUND)


def test_a_grammar_takes_only_its_commands():
    with pytest.raises(CommandError, match="unknown command 'gas'; known: mode$"):
        decode('gas bank on', (ModeCommand,))


def test_the_mode_report_round_trips_through_the_mode_status():
    report = ModeReport('mode_1b', 'capture', True, (('capture_t_s', '12.000'),), True,
                        (('em_driver', 'eea_select x B'), ('acds_controller', 'gain max_moment 1500.0'),
                         ('em_driver', 'eea_select y A')))
    value = report.encode()
    (status,) = value
    assert status == Status(OK, MODE_STATUS, 'mode_1b', MODE_STATUS, (
        ('mode', 'mode_1b'), ('cause', 'capture'), ('captured', 'true'), ('capture_t_s', '12.000'),
        ('run_complete', 'true'), ('command/em_driver', 'eea_select x B'),
        ('command/acds_controller', 'gain max_moment 1500.0'), ('command/em_driver', 'eea_select y A')))
    assert ModeReport.decode(value) == report
    assert mode_status(value, 'em_driver') == ('mode_1b', ['eea_select x B', 'eea_select y A'])
    assert run_complete(value) and not run_complete(ModeReport('mode_1a').encode()) and not run_complete(None)


def test_a_mode_status_reader_reads_what_mode_status_reads_and_rereads_a_new_value_only():
    read = ModeStatusReader('em_driver')
    assert read(None) == mode_status(None, 'em_driver') == (None, [])
    first = ModeReport('mode_1a', forwarded=(('em_driver', 'eea_select x B'),)).encode()
    kept = read(first)
    assert kept == ('mode_1a', ['eea_select x B']) and read(first) is kept  # the same object: not read again
    equal = ModeReport('mode_1a', forwarded=(('em_driver', 'eea_select x B'),)).encode()  # a node process's decode
    again = read(equal)
    assert again == kept and again is not kept  # another object: read again
    assert read(ModeReport('mode_1b').encode()) == ('mode_1b', []) and read(None) == (None, [])


def test_a_mode_logic_that_never_ends_a_run_sends_no_run_complete():
    value = ModeReport('sss_spin_idle', run_complete=None).encode()
    assert 'run_complete' not in dict(value[0].values)
    assert ModeReport.decode(value).run_complete is None and not run_complete(value)
    assert ModeReport.decode(()) is None and mode_status(None, 'em_driver') == (None, [])


@pytest.mark.parametrize('values', [
    (('mode', 'mode_1b'), ('cause', 'capture'), ('captured', 'true')),
    (('cause', ''), ('captured', 'false')),  # no mode key: the status message
    (('mode', 'mode_1a'), ('captured', 'maybe'), ('mode', 'mode_2'), ('cause', 'x'), ('cause', 'y')),  # first wins
    (),
])
def test_mode_state_reads_what_decode_reads(values):
    value = (Status(OK, MODE_STATUS, 'cruise', MODE_STATUS, values),)
    report = ModeReport.decode(value)
    assert mode_state(value) == (report.mode, report.cause, report.captured)
    assert mode_state(None) is None and mode_state(()) is None
