"""Emulated CANopen devices, the mapping file and the CAN log (spec §13), without a graph."""

import io
import struct
from pathlib import Path

import canopen
import pytest
from canopen_bus.canlog import CanLog, CanLogError, read_replay, recorded_rtf
from canopen_bus.device import EmulatedDevice
from canopen_bus.dictionary import DictionaryError, load_dictionary
from canopen_bus.mapping import load_mapping

MAPPING = Path(__file__).resolve().parents[4] / 'scenarios' / 'canopen' / 'oresat1_cards.yaml'


class Wire:
    """A client SDO transfer against one device, frame by frame (what a master sends, what the device answers)."""

    def __init__(self):
        self.frames: list[tuple[int, bytes]] = []
        self.dev = EmulatedDevice('adcs', load_dictionary('oresat1/adcs'), 0x38, lambda i, d: self.frames.append((i, d)),
                                  wall=lambda: 0.0)

    def request(self, data: bytes) -> bytes:
        self.frames.clear()
        self.dev.receive(0x638, data, 0.0)
        (cid, reply), = self.frames
        assert cid == 0x5B8
        return reply


def _abort_code(reply: bytes) -> int:
    assert reply[0] == 0x80, reply.hex()
    return struct.unpack_from('<I', reply, 4)[0]


def test_sdo_expedited_and_the_standard_abort_codes():
    w = Wire()
    # expedited download of 4 bytes to current_x_setpoint (0x4007:4), then upload it back
    assert w.request(bytes([0x23, 0x07, 0x40, 0x04]) + struct.pack('<i', -12345))[0] == 0x60
    reply = w.request(bytes([0x40, 0x07, 0x40, 0x04, 0, 0, 0, 0]))
    assert reply[0] & 0xE3 == 0x43 and struct.unpack_from('<i', reply, 4)[0] == -12345
    assert w.dev.get_raw(0x4007, 4) == -12345
    assert _abort_code(w.request(bytes([0x23, 0x00, 0x50, 0x01, 0, 0, 0, 0]))) == 0x06020000   # no object 0x5000
    assert _abort_code(w.request(bytes([0x23, 0x07, 0x40, 0x0C, 0, 0, 0, 0]))) == 0x06090011   # no subindex 12
    assert _abort_code(w.request(bytes([0x2B, 0x00, 0x40, 0x01, 1, 0, 0, 0]))) == 0x06010002   # gyro is read-only
    assert _abort_code(w.request(bytes([0x2B, 0x07, 0x40, 0x04, 1, 0, 0, 0]))) == 0x06070010   # 2 bytes into int32
    assert w.dev.sdo.aborts == {0x06020000: 1, 0x06090011: 1, 0x06010002: 1, 0x06070010: 1}
    assert w.dev.sdo.requests == 6
    lines = []
    w.dev.on_malformed = lines.append
    for _ in range(3):
        w.request(bytes([0x2B, 0x00, 0x40, 0x01, 1, 0, 0, 0]))
    assert lines == ['device adcs: SDO abort 0x06010002 (read-only object) for 0x4000:1 (named once per object and '
                     'code; counted)']


def test_sdo_segmented_upload_of_a_long_object():
    w = Wire()
    text = w.dev.node.get_data(0x3002, 2)  # versions.configs_version: '1.2.0', longer than an expedited 4 bytes
    assert text == b'1.2.0'
    reply = w.request(bytes([0x40, 0x02, 0x30, 0x02, 0, 0, 0, 0]))
    assert reply[0] == 0x41 and struct.unpack_from('<I', reply, 4)[0] == len(text)
    got, toggle = b'', 0
    while True:
        seg = w.request(bytes([0x60 | toggle << 4]) + bytes(7))
        n = 7 - ((seg[0] >> 1) & 7)
        got += seg[1:1 + n]
        toggle ^= 1
        if seg[0] & 1:
            break
    assert got == text


def test_tpdos_heartbeat_and_nmt_on_the_step_clock():
    sent: list[tuple[int, bytes]] = []
    dev = EmulatedDevice('adcs', load_dictionary('oresat1/adcs'), 0x38, lambda i, d: sent.append((i, d)))
    dev.boot()
    assert sent == [(0x738, b'\x00')] and dev.nmt_state == 'OPERATIONAL'
    dev.set_raw(0x4000, 1, -1234)
    sent.clear()
    ids = [dev.tick(k * 0.1) for k in range(21)]  # 2 s of 0.1 s steps: heartbeat and every TPDO at 1 s (the OD's)
    assert ids[0][0] == 0x738 and 0x1B8 in ids[0] and ids[5] == [] and 0x1B8 in ids[10] and 0x1B8 in ids[20]
    gyro = [d for i, d in sent if i == 0x1B8][0]
    assert struct.unpack('<hhh', gyro) == (-1234, 0, 0)
    assert dict(sent)[0x738] == b'\x05'  # heartbeat: operational
    # NMT stop (0x000: command 2, this node): heartbeat goes on with state 0x04, the TPDOs stop
    dev.receive(0x000, bytes([0x02, 0x38]), 0.0)
    sent.clear()
    ids = dev.tick(3.0)
    assert ids == [0x738] and sent == [(0x738, b'\x04')]
    dev.receive(0x000, bytes([0x01, 0x00]), 0.0)  # start all nodes
    assert 0x1B8 in dev.tick(4.0)


def _mapping(tmp_path: Path, objects: str, extra: str = '') -> Path:
    p = tmp_path / 'm.yaml'
    p.write_text(f'devices:\n  adcs:\n    dictionary: oresat1/adcs\n{extra}    objects:\n{objects}')
    return p


@pytest.mark.parametrize('objects, extra, needle', [
    ('      - {index: 0x4010, subs: [1, 2, 3], quantity: body_rate, si_per_count: 0.001, unit: rad/s}\n', '',
     'object 0x4010 not in its object dictionary'),
    ('      - {index: 0x4000, subs: [1, 2, 3], quantity: coil_current_setpoint, si_per_count: 1.0e-6, unit: A}\n', '',
     'is read-only'),
    ('      - {index: 0x4000, subs: [1, 2, 3], quantity: body_rate, si_per_count: 1.0e-4, unit: rad/s, full_scale: 8.73}\n',
     '', 'holds -32768..32767 counts'),
    ('      - {index: 0x4000, subs: [1, 2, 3], quantity: body_rate, si_per_count: 0.001, unit: deg/s}\n', '',
     'body_rate is in rad/s, the file says deg/s'),
    ('      - {index: 0x4000, subs: [1, 2, 3], quantity: spin, si_per_count: 0.001, unit: rad/s}\n', '',
     'quantity "spin"'),
    ('      []\n', '    tpdo_period_s: {42: 1.0}\n', 'names TPDO 42'),
])
def test_a_mapping_that_does_not_fit_is_one_line(tmp_path, objects, extra, needle):
    with pytest.raises(DictionaryError, match=needle) as info:
        load_mapping(_mapping(tmp_path, objects, extra))
    assert '\n' not in str(info.value)


def test_a_pdo_longer_than_8_bytes_is_refused(tmp_path):
    od = load_dictionary('oresat1/adcs')
    buf = io.StringIO()
    canopen.export_od(od, buf, doc_type='eds')
    text = buf.getvalue()
    head = text.index('[1A00sub0]')
    eds = text[:head] + text[head:].replace('DefaultValue=0x03', 'DefaultValue=0x05', 1)
    for sub in (4, 5):
        eds += f'\n[1A00sub{sub}]\nParameterName=mapping_object_{sub}\nObjectType=0x7\nDataType=0x0007\nAccessType=rw\n' \
               f'DefaultValue=0x40070120\nPDOMapping=0\n'
    (tmp_path / 'long.eds').write_text(eds)
    with pytest.raises(DictionaryError, match='TPDO 1 .*maps 112 bits, more than the 64'):
        load_mapping(_eds_mapping(tmp_path))


def _eds_mapping(tmp_path: Path) -> Path:
    p = tmp_path / 'eds.yaml'
    p.write_text('devices:\n  card:\n    dictionary: long.eds\n    node_id: 0x20\n    objects: []\n')
    return p


def test_the_shipped_mapping_fits_and_a_device_from_an_eds_serves(tmp_path):
    maps = load_mapping(MAPPING)
    assert [(m.name, m.node_id) for m in maps] == [('adcs', 0x38), ('gps', 0x34)]
    buf = io.StringIO()
    canopen.export_od(maps[0].od, buf, doc_type='eds')
    (tmp_path / 'adcs.eds').write_text(buf.getvalue())
    sent = []
    dev = EmulatedDevice('eds', load_dictionary('adcs.eds', tmp_path), 0x20, lambda i, d: sent.append((i, d)))
    dev.receive(0x620, bytes([0x40, 0x07, 0x40, 0x04, 0, 0, 0, 0]), 0.0)
    assert sent and sent[0][0] == 0x5A0 and sent[0][1][0] == 0x43


def test_the_can_log_reads_back_with_its_steps(tmp_path):
    log = CanLog(tmp_path / 'can.asc', 10.0)
    log.write(0, 100.0, 0x738, b'\x05', rx=False)
    log.write(3, 100.25, 0x638, bytes([0x23, 7, 0x40, 4, 1, 0, 0, 0]), rx=True)
    log.write(3, 100.26, 0x5B8, bytes([0x60, 7, 0x40, 4, 0, 0, 0, 0]), rx=False)
    log.close()
    assert read_replay(tmp_path / 'can.asc') == {3: [(100.25, 0x638, bytes([0x23, 7, 0x40, 4, 1, 0, 0, 0]))]}
    assert recorded_rtf(tmp_path / 'can.asc') == 10.0
    side = tmp_path / 'can.asc.steps.csv'
    side.write_text('\n'.join(side.read_text().splitlines()[:-1]) + '\n')
    with pytest.raises(CanLogError, match='3 frames but 2 rows'):
        read_replay(tmp_path / 'can.asc')


def test_the_contract_and_the_eds_come_from_the_dictionaries_the_cards_serve(tmp_path):
    from acds_common.scenario import load_scenario
    from canopen_bus import contract

    sc = load_scenario('oresat_c3_detumble')
    c: dict = {}
    contract.extend(sc, c, '')
    devices = c['canopen']['devices']
    assert [(d['device'], d['node_id'], d['heartbeat']['cob_id']) for d in devices] == [('adcs', '0x38', '0x738'),
                                                                                          ('gps', '0x34', '0x734')]
    gyro = next(o for o in devices[0]['objects'] if o['object'] == '0x4000:1')
    assert (gyro['type'], gyro['access'], gyro['od_unit'], gyro['si_per_count']) == ('INTEGER16', 'ro', 'deg/s', 1e-3)
    assert [p['cob_id'] for p in devices[1]['tpdos'][3:6]] == ['0x4B4', '0x1B5', '0x2B5']
    (tmp_path / 'gps.eds').write_text(contract.write('eds', sc, 'gps'))
    od = canopen.import_od(str(tmp_path / 'gps.eds'))
    assert od[0x4002][14].name == 'ecef_x' and od[0x1803][1].default & 0x7FF == 0x4B4
    with pytest.raises(ValueError, match='name one device'):
        contract.write('eds', sc, '')


def test_card_faults_silence_the_pdos_and_drop_or_delay_the_sdo_replies():
    w = Wire()
    w.dev.boot()
    w.dev.silenced = True
    w.frames.clear()
    assert w.dev.tick(0.0) == [0x738]  # the heartbeat goes on, no TPDO
    w.dev.sdo_lost = True
    w.frames.clear()
    w.dev.receive(0x638, bytes([0x40, 0x07, 0x40, 0x04, 0, 0, 0, 0]), 0.0)
    assert w.frames == [] and w.dev.sdo_dropped == 1
    w.dev.sdo_lost, w.dev.sdo_delay_s = False, 0.05
    w.dev.receive(0x638, bytes([0x40, 0x07, 0x40, 0x04, 0, 0, 0, 0]), 0.0)
    assert w.frames == []
    import time
    end = time.monotonic() + 5.0
    while not w.frames and time.monotonic() < end:
        time.sleep(0.01)
    assert w.frames and w.frames[0][0] == 0x5B8


def test_a_zero_axis_fault_reaches_the_bus_at_its_step():
    import copy
    import dataclasses

    from acds_common.scenario import load_scenario
    from acds_runtime.direct import DirectRun

    sc = load_scenario('oresat_c3_detumble')
    values = copy.copy(sc.values)
    values['can_bus'] = {**sc.values['can_bus'], 'fault': 'zero_axis', 'fault_object': 0x4004, 'fault_axis': 2,
                         'fault_time': 0.5}
    run = DirectRun(dataclasses.replace(sc, values=values), steps=10)
    run.run()
    adcs = run.steppers['canopen_cards'].devices['adcs']
    assert adcs.get_raw(0x4004, 3) == 0 and adcs.get_raw(0x4003, 3) != 0 and adcs.get_raw(0x4004, 1) != 0


def test_an_rpdo_writes_its_mapped_objects(tmp_path):
    od = load_dictionary('oresat1/adcs')
    buf = io.StringIO()
    canopen.export_od(od, buf, doc_type='eds')
    rpdo = ('\n[1400]\nParameterName=rpdo_1_communication\nObjectType=0x9\nSubNumber=3\n'
            '\n[1400sub0]\nParameterName=highest\nObjectType=0x7\nDataType=0x0005\nAccessType=const\nDefaultValue=2\n'
            '\n[1400sub1]\nParameterName=cob_id\nObjectType=0x7\nDataType=0x0007\nAccessType=rw\nDefaultValue=0x220\n'
            '\n[1400sub2]\nParameterName=transmission_type\nObjectType=0x7\nDataType=0x0005\nAccessType=rw\n'
            'DefaultValue=254\n'
            '\n[1600]\nParameterName=rpdo_1_mapping\nObjectType=0x9\nSubNumber=3\n'
            '\n[1600sub0]\nParameterName=highest\nObjectType=0x7\nDataType=0x0005\nAccessType=const\nDefaultValue=2\n'
            '\n[1600sub1]\nParameterName=m1\nObjectType=0x7\nDataType=0x0007\nAccessType=rw\nDefaultValue=0x40070420\n'
            '\n[1600sub2]\nParameterName=m2\nObjectType=0x7\nDataType=0x0007\nAccessType=rw\nDefaultValue=0x40070520\n')
    (tmp_path / 'rx.eds').write_text(buf.getvalue() + rpdo)
    dev = EmulatedDevice('rx', load_dictionary('rx.eds', tmp_path), 0x20, lambda i, d: None)
    dev.receive(0x220, struct.pack('<ii', 1000, -2000), 0.0)
    assert dev.get_raw(0x4007, 4) == 0  # not OPERATIONAL yet
    dev.boot()
    dev.receive(0x220, struct.pack('<ii', 1000, -2000), 0.0)
    assert (dev.get_raw(0x4007, 4), dev.get_raw(0x4007, 5)) == (1000, -2000)
    dev.receive(0x220, b'\x01', 0.0)
    assert dev.rpdo_errors == 1


def test_a_frame_the_canopen_services_cannot_read_is_one_line_and_the_device_goes_on():
    lines = []
    w = Wire()
    w.dev.on_malformed = lines.append
    for cid, data in ((0x000, b'\x01'), (0x638, b''), (0x638, b'\x40\x00')):
        w.dev.receive(cid, data, 0.0)
    assert w.dev.malformed == 3 and 'frame 0x000 [01] is not a valid CANopen message' in lines[0]
    assert sum('is not a valid CANopen message' in line for line in lines) == 3
    assert w.request(bytes([0x40, 0x07, 0x40, 0x04, 0, 0, 0, 0]))[0] == 0x43  # still serving
