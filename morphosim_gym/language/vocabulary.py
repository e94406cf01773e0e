"""The object categories and settings the scene generator implements: the single source of truth.

Each `Category` has its name (what the generator builds), synonyms and plural forms used by the
rule-based parser, a short phrase that the embedding grounder compares unknown nouns with, and an
optional habitat: the setting a scene gets when the text names none (a fish swims in water).

Settings are scene backgrounds. "table" is both a category and a setting: as a place ("on the
table", "across the table", "the camera circles the table") it is the tabletop setting; as a thing
that moves, has a colour or count, or is a motion's start or end ("the cat jumps onto the table")
it is an object. See `morphosim_gym.language.rules`.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Category", "CATEGORIES", "SETTINGS", "SETTING_WORDS", "DEFAULT_SETTING", "SettingLayout", "SETTING_LAYOUTS",
           "category_names",
           "setting_names", "noun_to_category", "word_to_setting", "singular", "is_plural_form"]


@dataclass(frozen=True)
class Category:
    """One object category of the generator's library.

    Attributes:
        name: the category name (also its canonical noun).
        synonyms: other singular nouns that mean this category in rule-based matching.
        plural: the plural of `name` (irregular ones matter: "fish", "sheep", "mice").
        description: a short phrase embedded for grounding unknown nouns.
        habitat: the setting used when the text names none, or None.
        sense: which WordNet sense of `name` (1 = its first in WordNet) the generator builds, when
            not the word's dominant ones (0): the lamp category is a table lamp, a piece of
            furniture, not any "artificial source of visible illumination" such as a light bulb.
    """

    name: str
    synonyms: tuple[str, ...] = ()
    plural: str = ""
    description: str = ""
    habitat: str | None = None
    sense: int = 0


def _c(name: str, synonyms: str = "", plural: str = "", description: str = "", habitat: str | None = None,
       sense: int = 0) -> Category:
    return Category(name, tuple(synonyms.split()), plural or name + "s", description or f"a {name}", habitat, sense)


_CATEGORY_LIST: tuple[Category, ...] = (
    _c("fish", "goldfish", "fish", "a fish swimming in water", "water"),
    _c("seaweed", "kelp algae", "seaweed", "seaweed, a water plant or kelp", "water"),
    _c("bus", "coach minibus schoolbus", "buses", "a bus, a large public passenger vehicle", "road"),
    _c("boat", "ship sailboat yacht canoe kayak ferry", "", "a boat or ship sailing on water", "water"),
    _c("car", "automobile taxi jeep suv", "", "a car, a passenger automobile", "road"),
    _c("ball", "football soccerball basketball sphere", "", "a round ball, a toy sphere"),
    _c("motorcycle", "motorbike", "", "a motorcycle, a motorbike", "road"),
    _c("sheep", "lamb", "sheep", "a sheep, a woolly farm animal", "grass"),
    _c("elephant", "", "", "an elephant, a large grey animal with a trunk", "grass"),
    _c("snowboarder", "skier", "", "a snowboarder riding down a snowy slope", "snow"),
    _c("cube", "block", "", "a cube, a block with square faces"),
    _c("plate", "dish platter", "", "a plate, a flat dish for food"),
    _c("table", "desk", "", "a table, a piece of furniture"),
    _c("mug", "", "", "a mug for hot drinks"),
    _c("bottle", "", "", "a bottle for liquids"),
    _c("box", "crate", "boxes", "a box, a cardboard container"),
    _c("robot", "droid", "", "a robot, a machine"),
    _c("person", "man woman boy girl child kid pedestrian human guy lady", "people",
       "a person, a human being"),
    _c("dog", "doggy hound", "", "a dog, a pet canine"),
    _c("cat", "", "", "a cat, a pet feline"),
    _c("tree", "", "", "a tree, a tall plant with a trunk"),
    _c("chair", "stool", "", "a chair, a seat"),
    _c("bicycle", "bike", "", "a bicycle, a bike with pedals", "road"),
    _c("bird", "", "", "a bird that flies", "sky"),
    _c("horse", "pony", "", "a horse", "grass"),
    _c("cow", "cattle", "", "a cow, cattle on a farm", "grass"),
    _c("truck", "lorry", "", "a truck, a lorry for cargo", "road"),
    _c("duck", "", "", "a duck, a water bird", "water"),
    _c("cup", "", "", "a cup for drinking"),
    _c("bowl", "", "", "a bowl, a round dish"),
    _c("apple", "", "", "an apple, a fruit"),
    _c("banana", "", "", "a banana, a yellow fruit"),
    _c("lamp", "", "", "a lamp, a light", sense=2),
    _c("vase", "", "", "a vase for flowers"),
    _c("book", "", "", "a book to read"),
    _c("cone", "", "", "a cone, a traffic cone"),
    _c("rock", "stone boulder", "", "a rock, a stone"),
    _c("house", "", "", "a house, a building"),
    _c("airplane", "plane aeroplane airliner jet aircraft", "", "an airplane, an aircraft that flies", "sky"),
    _c("train", "locomotive", "", "a train on a railway"),
)

class _Categories(dict):
    """The library's categories; indexing with an open-vocabulary category (a basic shape or
    "asset:<id>", see `open_vocab`) gives a generic entry, while iteration and `in` stay the library's."""

    def __missing__(self, key: str) -> Category:
        from .open_vocab import is_open_category
        if isinstance(key, str) and is_open_category(key):
            return Category(key, description=f"a {key}")
        raise KeyError(key)


CATEGORIES: dict[str, Category] = _Categories({c.name: c for c in _CATEGORY_LIST})

# Settings (backgrounds) and the words that name them.
SETTINGS: dict[str, tuple[str, ...]] = {
    "water": ("water", "waters", "underwater", "ocean", "oceans", "lake", "river", "sea", "seas", "pond",
              "stream", "aquarium", "waves", "reef", "seabed", "seafloor"),
    "road": ("road", "roads", "street", "streets", "highway", "freeway", "motorway", "avenue", "lane",
             "intersection", "city", "town"),
    "table": ("table", "tabletop", "kitchen", "desk", "counter", "countertop", "workbench"),
    "snow": ("snow", "snowy", "slope", "slopes", "mountain", "mountains", "ski", "glacier", "ice", "icy"),
    "grass": ("grass", "grassy", "field", "fields", "meadow", "meadows", "park", "landscape", "lawn",
              "pasture", "farm", "countryside", "garden", "forest", "savanna", "prairie", "hill", "hills", "hillside"),
    "sky": ("sky", "skies", "air", "clouds", "cloud", "cloudy", "midair"),
    "ground": ("ground", "floor", "pavement"),
    "sand": ("sand", "sandy", "beach", "desert", "dunes", "dune", "shore", "coast"),
    "indoor": ("indoor", "indoors", "room", "living", "bedroom", "hall", "office"),
}
DEFAULT_SETTING = "ground"


@dataclass(frozen=True)
class SettingLayout:
    """What a setting puts around the objects: what the generator builds and reconstruction reads.

    Attributes:
        label: the name of the setting's background object in a scene ("indoor" -> "floor").
        walls: closed by walls: what a frame shows above the horizon is a backdrop near the
            scene, not a sky (no sky panorama; estimated priors keep it as part of the setting).
        ground: a ground plane near enough to be seen as one (False up in the sky: everything
            but the objects is sky).
    """

    label: str
    walls: bool = False
    ground: bool = True


SETTING_LAYOUTS: dict[str, SettingLayout] = {
    "water": SettingLayout("water"),
    "underwater": SettingLayout("water"),       # the generator's water seen from below the surface
    "road": SettingLayout("road"),
    "table": SettingLayout("table", walls=True),
    "snow": SettingLayout("snow"),
    "grass": SettingLayout("grass"),
    "sky": SettingLayout("sky", ground=False),
    "ground": SettingLayout("ground"),
    "sand": SettingLayout("sand"),
    "indoor": SettingLayout("floor", walls=True),
}

SETTING_WORDS: dict[str, str] = {w: s for s, words in SETTINGS.items() for w in words}

def _plural(word: str) -> str:
    if word.endswith("y") and word[-2:-1] not in ("a", "e", "i", "o", "u"):
        return word[:-1] + "ies"
    if word.endswith(("s", "x", "z", "ch", "sh")):
        return word + "es"
    return word + "s"


_NOUNS: dict[str, tuple[str, bool]] = {}  # word -> (category, is_plural)
for _cat in _CATEGORY_LIST:
    _NOUNS[_cat.name] = (_cat.name, False)
    _NOUNS.setdefault(_cat.plural, (_cat.name, _cat.plural != _cat.name))
    for _s in _cat.synonyms:
        _NOUNS.setdefault(_s, (_cat.name, False))
        _NOUNS.setdefault(_plural(_s), (_cat.name, True))
# Irregular plurals and invariant nouns.
_NOUNS.update({"men": ("person", True), "women": ("person", True), "children": ("person", True),
               "people": ("person", True), "persons": ("person", True), "cattle": ("cow", True),
               "fishes": ("fish", True), "busses": ("bus", True)})


def category_names() -> list[str]:
    """The category names, in library order."""
    return list(CATEGORIES)


def setting_names() -> list[str]:
    """The setting names."""
    return list(SETTINGS)


def noun_to_category(word: str) -> tuple[str, bool] | None:
    """``(category, is_plural)`` for a noun of the rule-based vocabulary, or None."""
    return _NOUNS.get(word)


def word_to_setting(word: str) -> str | None:
    """The setting a word names ("ocean" -> "water"), or None."""
    return SETTING_WORDS.get(word)


def is_plural_form(word: str) -> bool:
    """Whether a vocabulary noun is a plural form ("balls", "people")."""
    hit = _NOUNS.get(word)
    return bool(hit and hit[1])


def singular(word: str) -> str:
    """A best-effort singular of an English noun ("boxes" -> "box", "puppies" -> "puppy")."""
    if word in CATEGORIES:
        return word
    irregular = {"people": "person", "men": "man", "women": "woman", "children": "child", "mice": "mouse",
                 "geese": "goose", "feet": "foot", "teeth": "tooth", "oxen": "ox", "leaves": "leaf",
                 "knives": "knife", "wolves": "wolf", "calves": "calf", "shelves": "shelf"}
    if word in irregular:
        return irregular[word]
    for cat in _CATEGORY_LIST:
        if word == cat.plural:
            return cat.name
    if len(word) > 4 and word.endswith("ies"):
        return word[:-3] + "y"
    if len(word) > 4 and word.endswith(("ches", "shes", "sses", "xes", "zes")):
        return word[:-2]
    if len(word) > 3 and word.endswith("s") and not word.endswith(("ss", "us", "is")):
        return word[:-1]
    return word
