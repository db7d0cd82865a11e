"""The numeric configuration compared between processes (acds_common.numeric_config): what counts, how it reads."""

from acds_common.numeric_config import COMPARED, differences, numeric_configuration


def test_the_host_and_the_pins_text_are_reported_not_compared():
    mine = numeric_configuration()
    assert set(COMPARED) < set(mine)
    assert differences(mine, {**mine, 'host': 'elsewhere', 'pin': 'NPY_DISABLE_CPU_FEATURES unset'}, 'the client') == []


def test_a_difference_names_the_item_both_values_and_for_simd_the_pin():
    mine = {**numeric_configuration(), 'simd': 'X86_V3'}
    theirs = {**mine, 'simd': 'X86_V3 X86_V4', 'numpy': '0.0', 'pin': "NPY_DISABLE_CPU_FEATURES=''"}
    assert differences(mine, theirs, 'the client') == [
        f'numpy 0.0 (the client: {mine["numpy"]})', 'numpy SIMD dispatch X86_V3 X86_V4 (the client: X86_V3)',
        "its pin: NPY_DISABLE_CPU_FEATURES=''"]
