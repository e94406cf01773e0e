"""Open vocabulary: basic shapes by name, real assets by embedding, nonsense gets candidates."""

import pytest

from morphosim_gym.errors import CommandError
from morphosim_gym.generate.compose import compose_scene
from morphosim_gym.generate.real_assets import asset_candidates
from morphosim_gym.language import parse


@pytest.fixture
def real(monkeypatch):
    monkeypatch.delenv("MORPHOSIM_ASSET_SOURCES", raising=False)
    if not asset_candidates("chair"):
        pytest.skip("needs the Sweet Home 3D furniture (apt install sweethome3d-furniture)")


def test_shapes_always_resolve():
    for shape in ("cylinder", "sphere", "torus", "capsule", "pyramid", "disc", "plank"):
        plan = parse(f"a green {shape}")
        if shape == "sphere":          # a vocabulary synonym of ball, which is a sphere
            assert plan.objects[0].category == "ball"
            continue
        assert plan.objects[0].category == shape
        scene = compose_scene(plan, 0).scene
        assert scene.objects[1].category == shape and scene.objects[1].asset is None


@pytest.mark.parametrize("text", ["a kangaroo", "a teapot", "a fire hydrant"])
def test_open_nouns_give_a_scene(real, text):
    plan = parse(text)
    scene = compose_scene(plan, 0).scene
    obj = scene.objects[1]
    assert obj.name == plan.objects[0].name
    if plan.objects[0].grounding == "open":
        assert obj.asset is not None and obj.category.startswith("asset:")
    assert scene.provenance.substitutions[0][0] == plan.objects[0].noun


def test_teapot_is_a_teapot(real):
    assert "teapot" in parse("a teapot").objects[0].category


def test_nonsense_lists_candidates(real):
    with pytest.raises(CommandError, match="florbnax.*Nearest shapes and assets: .+\\(0\\.\\d\\d\\)"):
        parse("a florbnax")


def test_name_match_beats_the_floor(real):
    # "fan": the asset names hold the word, the embedding alone is below the floor
    assert "fan" in parse("a fan").objects[0].category


def test_noun_list_has_300():
    from pathlib import Path
    nouns = [n for n in (Path(__file__).parent / "nouns_300.txt").read_text().splitlines() if n and n[0] != "#"]
    assert len(nouns) >= 300 and len(set(nouns)) == len(nouns)


def test_named_assets_beat_the_nearest_category(real):
    # "guitar" is nearer to the category rock (0.53) than to "Electric guitar" (0.51); the name decides
    assert "guitar" in parse("a guitar").objects[0].category
    assert parse("a spoon").objects[0].category.startswith("asset:")
    from morphosim_gym.language.open_vocab import ground_named
    assert ground_named("spider") is None                         # "Spider plant" is a plant
    assert "bunkbed" in ground_named("bunk bed").category          # the name without its space


def _needs_wordnet():
    from morphosim_gym.language import wordnet
    if not wordnet.available():
        pytest.skip("needs WordNet (apt install wordnet-base)")


def test_checked_level_refuses_what_nothing_shows(real, monkeypatch):
    _needs_wordnet()
    for spelling in ("checked", "strict"):                        # "strict": the old spelling, still read
        monkeypatch.setenv("MORPHOSIM_GROUNDING", spelling)
        with pytest.raises(CommandError, match="kangaroo.*Nearest shapes and assets: .+\\(0\\.\\d\\d\\)"):
            parse("a kangaroo")
        assert parse("an eagle").objects[0].category == "bird"       # a kind of bird (WordNet)
        assert parse("a kitten").objects[0].category == "cat"        # very similar (0.77)
    monkeypatch.setenv("MORPHOSIM_GROUNDING", "loose")
    with pytest.raises(ValueError, match="MORPHOSIM_GROUNDING"):
        parse("a tiger")
    with pytest.raises(ValueError, match="grounding"):
        parse("a tiger", grounding="loose")


def test_kind_level_stands_in_with_the_same_kind(real, monkeypatch):
    _needs_wordnet()
    from morphosim_gym.language.hypernyms import shared_kind
    from morphosim_gym.language.substitutions import SubstitutionWarning, plan_substitutions

    monkeypatch.delenv("MORPHOSIM_GROUNDING", raising=False)
    o = parse("a kangaroo").objects[0]                              # "kind" is the default
    assert o.grounding == "kind" and o.category != "duck"
    text = o.category if not o.category.startswith("asset:") else None
    assert shared_kind("kangaroo", text=None if text else _asset_name(o.category), category=text) is not None
    [sub] = plan_substitutions(parse("a kangaroo"))
    assert sub.kind == "stand-in" and sub.asked == "kangaroo"
    with pytest.warns(SubstitutionWarning, match="kangaroo.*stand-in of the same kind"):
        import morphosim_gym as ms
        ms.MorphoSim(reconstruction="oracle").parse("a kangaroo")
    with pytest.raises(CommandError, match="florbnax.*Nearest shapes and assets"):
        parse("a florbnax")                                          # WordNet knows no kind: refused
    nearest = parse("a kangaroo", grounding="nearest").objects[0]
    assert nearest.grounding in ("embedding", "open")                # the old default, by similarity only


def _asset_name(category: str) -> str:
    from morphosim_gym.generate.real_assets import asset_index
    return asset_index().get(category[len("asset:"):]).name


def test_zero_ad_animals_resolve_by_name(real):
    from morphosim_gym.assets.sources import ZeroADSource
    if ZeroADSource.discover() is None:
        pytest.skip("needs Debian 0ad-data")
    for noun in ("tiger", "whale", "giraffe", "polar bear"):
        assert parse(f"a {noun}").objects[0].category.startswith("asset:zero_ad/"), noun


def test_a_lizard_is_not_the_fantasy_dragon(real):
    # 0 A.D.'s Dragon is the mythical one (tagged "firedrake"): "a dragon" names it, "a lizard" does not
    from morphosim_gym.assets.sources import ZeroADSource
    if ZeroADSource.discover() is None:
        pytest.skip("needs Debian 0ad-data")
    assert parse("a dragon").objects[0].category == "asset:zero_ad/fauna/dragon"
    assert parse("a lizard").objects[0].category != "asset:zero_ad/fauna/dragon"


def _first(text):
    return parse(text).objects[0]


@pytest.mark.parametrize("text, name", [("a pair of sunglasses", "sunglasses"), ("a sunglasses", "sunglasses"),
                                        ("a chandelier", "chandelier lamp"), ("a nightstand", "bedside table")])
def test_assets_named_by_plural_apposition_or_tag(real, text, name):
    # a plural name, a "<noun> <near-synonym>" name, a rare tag: the asset the noun names, not a stand-in
    from morphosim_gym.generate.real_assets import asset_index
    o = _first(text)
    assert o.grounding == "open" and o.category.startswith("asset:")
    assert asset_index().get(o.category[len("asset:"):]).name.lower() == name


def test_modifier_names_are_not_the_noun(real):
    from morphosim_gym.language import open_vocab
    # "Dog house", "Spider plant", "Coffee machine", "Red orange juice", "Tomato sauce" are other things
    for noun in ("dog", "spider", "coffee", "orange", "tomato", "peach"):
        hit = open_vocab.ground_named(noun)
        assert hit is None or hit.text.lower().split()[-1].rstrip("s") == noun


def test_a_synonym_at_distance_zero_is_a_checked_match(real, monkeypatch):
    monkeypatch.delenv("MORPHOSIM_GROUNDING", raising=False)
    # WordNet: fireplug = fire hydrant, so "Fire hydrant" is no stand-in. (It was "a toilet" -> "Small
    # lavatory"; that asset is tagged washbasin, the lavatory sense it is, so it is no toilet:
    # test_noun_senses.py.)
    o = _first("a fireplug")
    assert o.grounding != "kind" and "hydrant" in o.category


def test_dominant_sense_picks_the_stand_in(real, monkeypatch):
    monkeypatch.delenv("MORPHOSIM_GROUNDING", raising=False)
    from morphosim_gym.generate.real_assets import asset_index
    o = _first("a turtle")          # the reptile (a crocodile stands in), never the turtleneck (a helmet)
    name = asset_index().get(o.category[len("asset:"):]).name.lower() if o.category.startswith("asset:") else ""
    assert "helmet" not in name and o.category != "tree"
    assert _first("a mango").category != "tree"
