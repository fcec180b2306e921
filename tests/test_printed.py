"""The printout comparison used for the README and stored tables."""

from tests.printed import line_in, number_mismatch, same_printout


def test_last_digit_moves_but_words_and_integers_do_not():
    line = "  [rank[O, IbarOG]=5; rank O=3; q=2; margin_decades=6.6]"
    assert number_mismatch(line.replace("6.6", "6.5"), line) is None
    assert number_mismatch(line.replace("6.6", "6.4"), line) is not None       # two units
    assert number_mismatch(line.replace("=5;", "=4;"), line) is not None       # an integer
    assert number_mismatch(line.replace("rank O", "rank P"), line) is not None  # the text
    assert number_mismatch("x 1.26095e-03", "x 1.26096e-03") is None
    assert number_mismatch("x 1.26095e-03", "x 1.26098e-03") is not None
    assert number_mismatch("45.57%", "45.56%") is None


def test_printouts_and_tables():
    assert same_printout("a 1.0\nb 2.00\n", "a 1.1\nb 2.01") == []
    assert same_printout("a 1.0\n", "a 1.0\nb 2") == ["1 lines printed, 2 expected"]
    table = "| PIO | 90 | 4.602 | 2.109 |\n| other | 1 | 2.0 | 3.0 |"
    assert line_in("| PIO | 90 | 4.603 | 2.109 |", table)
    assert not line_in("| PIO | 91 | 4.602 | 2.109 |", table)
