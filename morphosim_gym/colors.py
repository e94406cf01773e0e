"""Colour names to RGB: what people mean by the common names, the 148 CSS names, extras, modifiers.

A colour phrase is an optional modifier followed by a base name:

- base names: every CSS Color Module Level 4 named colour (148, "grey" and "gray" spellings both),
  written as one word or as separate words ("light blue" == "lightblue", "dark olive green" ==
  "darkolivegreen"), plus the extras in `EXTRA_COLORS` ("golden", "cream", "burgundy"...).
  A multi-word CSS name wins over modifier + base: "light blue" is CSS lightblue.
- common names mean what people mean: `COMMON_COLORS` overrides the CSS value of the everyday names
  whose CSS value people see as another colour (CSS brown a52a2a reads as dark red, CSS purple as
  magenta, CSS green as dark green, CSS beige and khaki as off-white). The CSS value stays available
  when asked for exactly: ``css:<name>`` ("a css:brown dog", "make it css:dark olive green") is the
  CSS Color Module value, whatever the table says.
- modifiers (applied to the base RGB, deterministic, results stay in [0, 1]):
  ``light``  mixes 50 % with white, ``pale`` mixes 70 % with white, ``dark`` multiplies by 0.55,
  ``bright`` scales so that the largest channel is 1 (full value; black becomes 0.25 grey). Synonyms: deep -> dark, pastel -> pale, vivid -> bright.

`ColorSpec.name` is the canonical phrase ("lightblue", "pale red", "golden"), `rgb` the value.
"""

from __future__ import annotations

from typing import Sequence

__all__ = ["CSS_COLORS", "CSS_PREFIX", "COMMON_COLORS", "EXTRA_COLORS", "COLOR_MODIFIERS", "MODIFIER_SYNONYMS", "color_rgb",
           "apply_modifier", "match_color", "is_color_word", "known_color_names"]

# CSS named colours (CSS Color Module Level 4), as hex.
_CSS_HEX = """
aliceblue f0f8ff antiquewhite faebd7 aqua 00ffff aquamarine 7fffd4 azure f0ffff beige f5f5dc bisque ffe4c4
black 000000 blanchedalmond ffebcd blue 0000ff blueviolet 8a2be2 brown a52a2a burlywood deb887 cadetblue 5f9ea0
chartreuse 7fff00 chocolate d2691e coral ff7f50 cornflowerblue 6495ed cornsilk fff8dc crimson dc143c cyan 00ffff
darkblue 00008b darkcyan 008b8b darkgoldenrod b8860b darkgray a9a9a9 darkgreen 006400 darkgrey a9a9a9
darkkhaki bdb76b darkmagenta 8b008b darkolivegreen 556b2f darkorange ff8c00 darkorchid 9932cc darkred 8b0000
darksalmon e9967a darkseagreen 8fbc8f darkslateblue 483d8b darkslategray 2f4f4f darkslategrey 2f4f4f
darkturquoise 00ced1 darkviolet 9400d3 deeppink ff1493 deepskyblue 00bfff dimgray 696969 dimgrey 696969
dodgerblue 1e90ff firebrick b22222 floralwhite fffaf0 forestgreen 228b22 fuchsia ff00ff gainsboro dcdcdc
ghostwhite f8f8ff gold ffd700 goldenrod daa520 gray 808080 green 008000 greenyellow adff2f grey 808080
honeydew f0fff0 hotpink ff69b4 indianred cd5c5c indigo 4b0082 ivory fffff0 khaki f0e68c lavender e6e6fa
lavenderblush fff0f5 lawngreen 7cfc00 lemonchiffon fffacd lightblue add8e6 lightcoral f08080 lightcyan e0ffff
lightgoldenrodyellow fafad2 lightgray d3d3d3 lightgreen 90ee90 lightgrey d3d3d3 lightpink ffb6c1
lightsalmon ffa07a lightseagreen 20b2aa lightskyblue 87cefa lightslategray 778899 lightslategrey 778899
lightsteelblue b0c4de lightyellow ffffe0 lime 00ff00 limegreen 32cd32 linen faf0e6 magenta ff00ff maroon 800000
mediumaquamarine 66cdaa mediumblue 0000cd mediumorchid ba55d3 mediumpurple 9370db mediumseagreen 3cb371
mediumslateblue 7b68ee mediumspringgreen 00fa9a mediumturquoise 48d1cc mediumvioletred c71585
midnightblue 191970 mintcream f5fffa mistyrose ffe4e1 moccasin ffe4b5 navajowhite ffdead navy 000080
oldlace fdf5e6 olive 808000 olivedrab 6b8e23 orange ffa500 orangered ff4500 orchid da70d6 palegoldenrod eee8aa
palegreen 98fb98 paleturquoise afeeee palevioletred db7093 papayawhip ffefd5 peachpuff ffdab9 peru cd853f
pink ffc0cb plum dda0dd powderblue b0e0e6 purple 800080 rebeccapurple 663399 red ff0000 rosybrown bc8f8f
royalblue 4169e1 saddlebrown 8b4513 salmon fa8072 sandybrown f4a460 seagreen 2e8b57 seashell fff5ee
sienna a0522d silver c0c0c0 skyblue 87ceeb slateblue 6a5acd slategray 708090 slategrey 708090 snow fffafa
springgreen 00ff7f steelblue 4682b4 tan d2b48c teal 008080 thistle d8bfd8 tomato ff6347 turquoise 40e0d0
violet ee82ee wheat f5deb3 white ffffff whitesmoke f5f5f5 yellow ffff00 yellowgreen 9acd32
"""


def _hex_table(text: str) -> dict[str, tuple[float, float, float]]:
    words = text.split()
    out = {}
    for name, hx in zip(words[0::2], words[1::2]):
        out[name] = tuple(round(int(hx[i:i + 2], 16) / 255.0, 6) for i in (0, 2, 4))
    return out


CSS_COLORS: dict[str, tuple[float, float, float]] = _hex_table(_CSS_HEX)
assert len(CSS_COLORS) == 148, len(CSS_COLORS)

# Common colour words that are not CSS names.
EXTRA_COLORS: dict[str, tuple[float, float, float]] = _hex_table("""
golden ffd700 bronze cd7f32 copper b87333 cream fffdd0 burgundy 800020 mustard ffdb58 charcoal 36454f
emerald 50c878 scarlet ff2400 amber ffbf00 ruby e0115f mauve e0b0ff
""")

# Everyday names as people picture them (sRGB; each replaces the CSS value of the bare name, the CSS
# value stays reachable as "css:<name>"). Names whose CSS value already reads right (red, blue,
# yellow, orange-ish tan, navy, maroon, olive, grey, silver, pink-ish...) are listed when their CSS
# value is off: brown, beige, khaki, purple, violet, green, orange, pink, gold.
COMMON_COLORS: dict[str, tuple[float, float, float]] = _hex_table("""
brown 8b5a2b beige e1c699 khaki c3b091 purple 7f3fbf violet 7f00ff green 22a033 orange ff8c1a pink ff99bb
gold d4af37 golden d4af37
""")
CSS_PREFIX = "css:"

COLOR_MODIFIERS: tuple[str, ...] = ("light", "dark", "pale", "bright")
MODIFIER_SYNONYMS: dict[str, str] = {"deep": "dark", "pastel": "pale", "vivid": "bright"}

_ALL = {**CSS_COLORS, **EXTRA_COLORS, **COMMON_COLORS}
# Multi-word spellings of CSS names, keyed by their words ("light", "blue") -> "lightblue".
_LONGEST_NAME_WORDS = 4
_BASIC = {"red", "green", "blue", "yellow", "orange", "purple", "pink", "brown", "gray", "grey", "white", "black"}


def known_color_names() -> list[str]:
    """All base colour names (CSS and extras), sorted."""
    return sorted(_ALL)


def _css_name(word: str) -> str | None:
    """The CSS name of a "css:<name>" word ("css:brown" -> "brown"), else None."""
    if word.startswith(CSS_PREFIX) and word[len(CSS_PREFIX):].replace(" ", "") in CSS_COLORS:
        return word[len(CSS_PREFIX):].replace(" ", "")
    return None


def is_color_word(word: str) -> bool:
    """Whether `word` alone names a base colour ("brown", "css:brown")."""
    return word in _ALL or _css_name(word) is not None


def apply_modifier(rgb: Sequence[float], modifier: str) -> tuple[float, float, float]:
    """Apply a colour modifier ("light", "dark", "pale", "bright") to an RGB triple in [0, 1]."""
    modifier = MODIFIER_SYNONYMS.get(modifier, modifier)
    r, g, b = (float(x) for x in rgb)
    if modifier == "light":
        out = [c + 0.5 * (1.0 - c) for c in (r, g, b)]
    elif modifier == "pale":
        out = [c + 0.7 * (1.0 - c) for c in (r, g, b)]
    elif modifier == "dark":
        out = [0.55 * c for c in (r, g, b)]
    elif modifier == "bright":
        m = max(r, g, b)
        if m <= 0.0:
            out = [0.25, 0.25, 0.25]
        else:
            out = [c / m for c in (r, g, b)]
    else:
        raise ValueError(f"Expected a colour modifier in {COLOR_MODIFIERS}, found {modifier!r}")
    return tuple(round(min(1.0, max(0.0, c)), 6) for c in out)


def color_rgb(name: str) -> tuple[float, float, float]:
    """RGB of a canonical colour name such as "red", "lightblue" or "pale red".

    Raises:
        ValueError: the name is not a known colour phrase.
    """
    name = " ".join(name.lower().split())
    css = _css_name(name.replace(": ", ":"))
    if css is not None:
        return CSS_COLORS[css]
    if name.replace(" ", "") in _ALL:
        return _ALL[name.replace(" ", "")]
    parts = name.split(" ", 1)
    if len(parts) == 2:
        mod = MODIFIER_SYNONYMS.get(parts[0], parts[0])
        base = parts[1].replace(" ", "")
        if mod in COLOR_MODIFIERS and base in _ALL:
            return apply_modifier(_ALL[base], mod)
    raise ValueError(f"Expected a colour name (a CSS colour such as 'red' or 'lightblue', optionally after "
                     f"light/dark/pale/bright, or 'css:<name>' for the exact CSS value), found {name!r}")


def match_color(words: Sequence[str], start: int = 0) -> tuple[str, tuple[float, float, float], int] | None:
    """Match a colour phrase at ``words[start:]``.

    Returns ``(canonical_name, rgb, n_words)`` for the longest match, or None. Multi-word CSS names
    are tried before modifier + base ("light blue" -> "lightblue"); a modifier may be followed by a
    one- or multi-word base ("pale sky blue" -> "pale skyblue").
    """
    n = len(words)
    css = _css_name(words[start]) if start < n else None
    if css is not None:
        return CSS_PREFIX + css, CSS_COLORS[css], 1
    for k in range(min(_LONGEST_NAME_WORDS, n - start), 0, -1):
        joined = "".join(words[start:start + k])
        if joined in _ALL:
            # "navy blue", "tomato red": a basic colour word after a name is part of it
            if start + k < n and words[start + k] in _BASIC and joined not in _BASIC:
                return joined, _ALL[joined], k + 1
            return joined, _ALL[joined], k
    if start < n:
        mod = MODIFIER_SYNONYMS.get(words[start], words[start])
        if mod in COLOR_MODIFIERS:
            for k in range(min(_LONGEST_NAME_WORDS, n - start - 1), 0, -1):
                joined = "".join(words[start + 1:start + 1 + k])
                if joined in _ALL:
                    return f"{mod} {joined}", apply_modifier(_ALL[joined], mod), k + 1
    return None
