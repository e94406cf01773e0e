"""FlightGear's scenery and AI models (Debian `flightgear-data-models`): y-up AC3D meshes with PNG,
SGI and DDS textures, under `/usr/share/games/flightgear/Models`.

The package holds ~520 models, many of them clouds, light cones and airport furniture; the useful
ones are named in `MODELS`, each looked at in a render: aircraft, vehicles, locomotives, ships,
buoys, towers and buildings. A model's row gives its name, category (one of the generator's where
the thing is a kind of it), tags, real-world longest side (the record's `size_m` keeps the file's
proportions at that size), the turn that makes it face the asset layer's front, its unit and the
objects to leave out.

Frames: every file is y-up; a vehicle's front points to the file's -x, so `yaw` (degrees about the
file's y axis, right-handed) is 90 by default, which turns -x to +z, the front of a y-up asset
(`frame.py`: it faces -y in the object frame, the camera; a moving one turns to +x). Ships converted
from SAVAGE run along the file's z axis and get their own turn. Units are metres except the `*1x.ac`
files (inches) and the SAVAGE sailing boats (feet). Ship wakes and shadows are flat planes far larger
than the hull: objects named like them are always left out (`ALWAYS_SKIP`), as are a row's `skip`.

Licences: GPL-2.0-or-later (FlightGear's data), except the models a folder's `readme.savage`
lists, converted from the NPS SAVAGE project, which are BSD-3-Clause; each record carries its own.
Gaussians or saved scenes made from these meshes are derived works: redistributed, they carry
those terms.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ..ac3d import read_ac3d
from ..frame import UP_ROTATIONS
from ..record import AssetRecord
from .base import FileStat, file_stats, warn_skip

__all__ = ["ALWAYS_SKIP", "DEFAULT_ROOT", "LICENCE", "MODELS", "SAVAGE_LICENCE", "FlightGearSource", "FlightGearModel",
           "model_licence", "yaw_rotation"]

DEFAULT_ROOT = "/usr/share/games/flightgear/Models"
LICENCE = "GPL-2.0-or-later (FlightGear data, Debian flightgear-data-models)"
SAVAGE_LICENCE = "BSD-3-Clause (NPS SAVAGE project models, converted for FlightGear)"
SAVAGE_README = "readme.savage"
ALWAYS_SKIP = ("wake", "shadow")       # flat planes around a ship or under an aircraft
INCH, FOOT = 0.0254, 0.3048
MAX_FILE_BYTES = 16 * 1024 * 1024


@dataclass(frozen=True)
class FlightGearModel:
    """One usable model of the package.

    Attributes:
        file: the `.ac` file under the Models folder.
        name: what it is, as people name it ("Double-decker bus").
        category: the generator's category it is a kind of ("bus"), else its own ("helicopter").
        tags: other words for it (model names, synonyms).
        longest_m: the real thing's longest side in metres, as modelled (rotors, masts included).
        yaw: degrees about the file's y axis that turn its front to the file's +z.
        unit: metres per file unit.
        skip: regular expressions of object names to leave out, besides `ALWAYS_SKIP`.
    """

    file: str
    name: str
    category: str
    tags: tuple[str, ...]
    longest_m: float
    yaw: int = 90
    unit: float = 1.0
    skip: tuple[str, ...] = ()


def _m(file: str, name: str, category: str, tags: str, longest_m: float, **kw) -> FlightGearModel:
    return FlightGearModel(file, name, category, tuple(t.strip() for t in tags.split(",") if t.strip()), longest_m, **kw)


_HOSE = ("^hose$", "^drogue$")       # a tanker aircraft's refuelling hose, trailed far behind it

# asset id (after "flightgear/") -> model
MODELS: dict[str, FlightGearModel] = {
    # ---- aircraft
    "aircraft/h60": _m("Aircraft/H-60.ac", "Military helicopter", "helicopter",
                       "helicopter, Seahawk, H-60, Black Hawk, navy helicopter", 17.5),    # rotors at 45 degrees
    "aircraft/dauphin": _m("Aircraft/dauphin.ac", "Rescue helicopter", "helicopter",
                           "helicopter, Dauphin, coast guard helicopter", 13.7),
    "aircraft/kc135": _m("Geometry/KC135/KC135.ac", "Jet airliner", "airplane",
                         "airliner, jetliner, Boeing 707, KC-135, four-engine jet", 46.6),
    "aircraft/f15": _m("Aircraft/F-15-lowpoly.ac", "Fighter jet", "airplane",
                       "fighter, fighter plane, warplane, F-15 Eagle", 19.4),
    "aircraft/kc130": _m("Geometry/KC-130/KC-130.ac", "Cargo plane", "airplane",
                         "transport plane, turboprop, Hercules, KC-130, military transport", 40.4, skip=_HOSE),
    "aircraft/ka6d": _m("Geometry/KA6-D/KA6-D.ac", "Navy jet", "airplane",
                        "attack aircraft, A-6 Intruder, KA-6D, carrier jet, warplane", 16.7, skip=_HOSE),
    "aircraft/a4": _m("Geometry/A4-F/a4-f-tanker.ac", "Light attack jet", "airplane",
                      "A-4 Skyhawk, jet, warplane", 12.9, skip=_HOSE),
    "aircraft/rocket": _m("Geometry/rocket.ac", "Rocket", "rocket", "space rocket, launch vehicle", 22.1),
    "aircraft/missile": _m("Geometry/Aim91x.ac", "Missile", "missile",
                           "air-to-air missile, Sidewinder, AIM-9", 2.85, unit=INCH),
    "aircraft/bomb": _m("Geometry/mk82.ac", "Bomb", "bomb", "aerial bomb, Mk 82", 2.2),
    # ---- people
    "people/testpilot": _m("Aircraft/testpilot.ac", "Test pilot", "person", "pilot, aviator, airman", 1.15),
    "people/parachutist": _m("Geometry/parachuter.ac", "Parachutist", "parachutist",      # 6.4 m with its chute
                             "parachuter, skydiver, parachute, person", 6.4),
    # ---- road and airport vehicles
    "vehicles/double_decker": _m("Transport/110Bus.ac", "Double-decker bus", "bus",
                                 "double-decker, city bus, bus", 10.5),
    "vehicles/fire_truck": _m("Airport/Vehicle/hoskosh-ti-1500.ac", "Fire truck", "truck",
                              "fire engine, airport crash tender, Oshkosh", 9.3),
    "vehicles/humvee": _m("Military/humvee-pickup-odrab-low-poly.ac", "Humvee", "car",
                          "military vehicle, Humvee pickup, jeep, HMMWV", 4.7),
    "vehicles/tug_douglas": _m("Airport/Pushback/Douglas.ac", "Aircraft tug", "aircraft tug",
                               "tow tractor, pushback tug, aircraft tractor", 7.7),
    "vehicles/tug_goldhofer": _m("Airport/Pushback/Goldhofert.ac", "Towbarless aircraft tug", "aircraft tug",
                                 "tow tractor, pushback tug, Goldhofer", 9.1),
    "vehicles/tug_military": _m("Airport/Pushback/Military.ac", "Military aircraft tug", "aircraft tug",
                                "tow tractor, pushback tug", 11.1),
    "vehicles/tow_tractor": _m("Airport/Pushback/Forklift.ac", "Tow tractor", "aircraft tug",
                               "baggage tractor, tug, tow bar", 4.8),
    "vehicles/mule": _m("Geometry/Nimitz/Models/mule-11.ac", "Aircraft tow tractor", "aircraft tug",
                        "tow tractor, carrier deck tractor, aircraft tug, mule", 4.9),
    "vehicles/crane": _m("Geometry/Nimitz/Models/deck-crane.ac", "Mobile crane", "crane",
                         "crane, crash crane, Grove crane", 17.1),
    # ---- railway
    "rail/class66": _m("Transport/Class_66.ac", "Diesel locomotive", "train",
                       "locomotive, Class 66, freight locomotive, engine", 21.4),
    "rail/a4": _m("Transport/locomotive-A4.ac", "Steam locomotive", "train",
                  "locomotive, LNER A4, Mallard, steam engine", 14.2),
    "rail/ice3": _m("Transport/ICE3firstcar.ac", "High-speed train", "train",
                    "bullet train, ICE 3, Intercity-Express, power car", 25.9, skip=("^sphere$",)),
    "rail/coach": _m("Transport/lner-teak-first-class-coach.ac", "Railway carriage", "rail car",
                     "passenger coach, railway coach, LNER teak coach", 18.7),
    "rail/ore_wagon": _m("Transport/wagon-ore.ac", "Freight wagon", "rail car",
                         "ore wagon, goods wagon, hopper car, freight car", 8.8),
    # ---- boats and ships
    "ships/container_ship": _m("Maritime/Civilian/ContainerShip.ac", "Container ship", "ship",
                               "containership, cargo ship, freighter", 240.0),
    "ships/tanker": _m("Maritime/Civilian/Tanker.ac", "Oil tanker", "ship", "tanker, tank ship, cargo ship", 240.0),
    "ships/cruise_ship": _m("Maritime/Civilian/CruiseShip.ac", "Cruise ship", "ship",
                            "cruise liner, ocean liner, passenger ship", 215.0),
    "ships/freighter": _m("Maritime/Civilian/Freighter.ac", "Freighter", "ship",
                          "cargo ship, merchant ship, merchantman", 252.0),
    "ships/ferry": _m("Maritime/Civilian/FerryBoat1.ac", "Ferry", "boat", "ferryboat, car ferry", 179.0),
    "ships/large_ferry": _m("Maritime/Civilian/LargeFerry.ac", "Passenger ferry", "boat", "ferry, ferryboat", 88.0,
                            yaw=180),
    "ships/trawler": _m("Maritime/Civilian/Trawler.ac", "Trawler", "boat", "fishing boat, fishing vessel", 43.2,
                        skip=("^(cylinder0[23]|object(08|09|10|11))$",)),      # its trawl net's floats
    "ships/large_trawler": _m("Maritime/Civilian/LargeTrawler.ac", "Large trawler", "boat",
                              "trawler, fishing boat, fishing vessel", 69.5),
    "ships/barge": _m("Maritime/Civilian/barge.ac", "Barge", "boat", "flatboat, cargo barge", 64.0, yaw=0),
    "ships/sailboat": _m("Maritime/Civilian/SailBoatUnderSail.ac", "Sailboat", "boat",
                         "sailing boat, sloop, sailing yacht", 18.5, unit=FOOT),
    "ships/yacht": _m("Maritime/Civilian/SailBoatUnderPower11m.ac", "Yacht", "boat",
                      "sailing yacht, sailboat under power", 18.2),
    "ships/frigate": _m("Maritime/Military/OliverPerryFFG.ac", "Frigate", "ship",
                        "warship, Oliver Hazard Perry frigate, naval ship", 138.0),
    "ships/cruiser": _m("Maritime/Military/CG-57/CG57.ac", "Cruiser", "ship",
                        "warship, guided missile cruiser, Ticonderoga, naval ship", 173.0),
    "ships/carrier": _m("Geometry/Nimitz/nimitz.ac", "Aircraft carrier", "ship",
                        "carrier, flattop, warship, Nimitz", 333.0),
    "ships/landing_craft": _m("Maritime/Military/LCM6.ac", "Landing craft", "boat",
                              "LCM-6, landing boat, amphibious craft", 17.1, yaw=180, unit=0.702),  # drawn 1.42x
    "ships/liferaft": _m("Maritime/Misc/liferaft4m.ac", "Life raft", "boat", "liferaft, raft, inflatable raft", 4.0, yaw=0),
    # ---- at sea
    "sea/buoy": _m("Maritime/Misc/Buoy-Conical-Yellow.ac", "Buoy", "buoy", "marker buoy, navigation buoy", 6.4),
    "sea/red_buoy": _m("Maritime/Misc/RedBuoy.ac", "Red buoy", "buoy", "buoy, channel marker", 2.25),
    "sea/oil_rig": _m("Maritime/Misc/OilRig.ac", "Oil rig", "oil rig", "oil platform, drilling rig", 75.7),
    "sea/iceberg": _m("Maritime/Ice/iceberg1.ac", "Iceberg", "iceberg", "berg, floating ice", 138.0),
    "sea/pier": _m("Maritime/Misc/pier_50m.ac", "Pier", "pier", "jetty, wharf, quay", 51.0),
    "sea/beacon": _m("Maritime/Misc/left_bank_beacon.ac", "Channel beacon", "beacon",
                     "navigation beacon, day marker", 15.3),
    # ---- towers and buildings
    "buildings/control_tower": _m("Geometry/Towerax.ac", "Control tower", "tower",
                                  "air traffic control tower, airport tower", 71.9),
    "buildings/water_tower": _m("Buildings/water-tower.ac", "Water tower", "tower", "water tank", 44.0),
    "buildings/cooling_tower": _m("Power/coolingtower.ac", "Cooling tower", "tower", "power station tower", 131.3),
    "buildings/church": _m("Buildings/big-church.ac", "Church", "church", "church building, chapel", 30.8),
    "buildings/barn": _m("Agriculture/red-barn.ac", "Barn", "barn", "red barn, farm building", 16.0),
    "buildings/silo": _m("Agriculture/silo.ac", "Silo", "silo", "grain silo, farm silo", 17.8),
    "buildings/petrol_station": _m("Commercial/Petrolstation1.ac", "Petrol station", "petrol station",
                                   "gas station, filling station, service station", 22.6, yaw=0),
    "buildings/farmhouse": _m("Agriculture/farmhouse1.ac", "Farmhouse", "house", "farm house, house", 19.2),
    "buildings/village_house": _m("Residential/germanvillagehouse1.ac", "Village house", "house",
                                  "house, cottage", 15.0),
    "buildings/bungalow": _m("Residential/MontHse1Red_Tile_Yellow.ac", "Bungalow", "house", "house, single-storey house",
                             12.0, yaw=0),
    "buildings/cottage": _m("Residential/MontserratHse2White.ac", "Cottage", "house", "house, white house", 12.0),
    "buildings/semi_detached": _m("Residential/germansemidetached1.ac", "Semi-detached house", "house",
                                  "house, duplex, two-family house", 16.3, yaw=0),
    "buildings/house": _m("Agriculture/foursquare.ac", "House", "house", "two-storey house, home", 9.6),
    "buildings/school": _m("Buildings/brick-school.ac", "School", "building", "school building, schoolhouse", 60.0,
                           yaw=0),
    "buildings/shop": _m("Buildings/shop.ac", "Shop", "building", "store, timber-framed shop", 9.9, yaw=0),
    "buildings/skyscraper": _m("Commercial/tower-glass-dark-blue.ac", "Skyscraper", "skyscraper",
                               "tower block, high-rise, office tower", 212.3),
    "buildings/office": _m("Commercial/small-glass-office-building.ac", "Office building", "building",
                           "office block, glass building", 30.0),
    "buildings/factory": _m("Buildings/factory.ac", "Factory", "building", "factory building, plant, works", 80.0),
    "props/flag": _m("Geometry/Ensign.ac", "Flag", "flag", "ensign, American flag, US flag", 2.85, yaw=0),
    "props/jet_bridge": _m("Airport/Jetway/generic.ac", "Jet bridge", "jet bridge",
                           "jetway, boarding bridge, airport gate", 22.3),
}


def yaw_rotation(degrees: float) -> np.ndarray:
    """The right-handed turn about the file's y (up) axis, row-major. [3, 3]"""
    a = math.radians(degrees)
    c, s = round(math.cos(a), 12), round(math.sin(a), 12)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def model_licence(path: Path) -> str:
    """The licence of a model file: SAVAGE's BSD-3-Clause when its folder's `readme.savage` lists
    it, else FlightGear's GPL-2.0-or-later."""
    try:
        listed = (path.parent / SAVAGE_README).read_text(encoding="latin-1").split()
    except OSError:
        return LICENCE
    return SAVAGE_LICENCE if path.name in listed else LICENCE


class FlightGearSource:
    """The models of `MODELS` found under a FlightGear `Models` folder (or one laid out like it)."""

    name = "flightgear"

    def __init__(self, root: str | os.PathLike = DEFAULT_ROOT) -> None:
        self.root = Path(root)

    @property
    def selection(self) -> str:
        """A digest of `MODELS` and `ALWAYS_SKIP` (part of the index's cache key: an edited table re-reads)."""
        table = json.dumps([{k: asdict(m) for k, m in MODELS.items()}, ALWAYS_SKIP], sort_keys=True)
        return hashlib.sha256(table.encode()).hexdigest()[:16]

    @classmethod
    def discover(cls) -> FlightGearSource | None:
        return cls() if Path(DEFAULT_ROOT).is_dir() else None

    def fingerprint(self) -> list[FileStat]:
        return file_stats([self.root / m.file for m in MODELS.values()] +
                          [self.root / Path(m.file).parent / SAVAGE_README for m in MODELS.values()])

    def records(self) -> list[AssetRecord]:
        out = []
        for rid, model in MODELS.items():
            path = self.root / model.file
            if not path.is_file():          # not in this version of the package
                continue
            try:
                out.append(self._record(rid, model, path))
            except (OSError, ValueError) as exc:
                warn_skip(path, f"FlightGear model does not convert ({type(exc).__name__}: {exc})")
        return out

    def _record(self, rid: str, model: FlightGearModel, path: Path) -> AssetRecord:
        if path.stat().st_size > MAX_FILE_BYTES:
            raise ValueError(f"above {MAX_FILE_BYTES >> 20} MiB")
        skip = (*ALWAYS_SKIP, *model.skip)
        bounds = read_ac3d(path.read_bytes(), str(path), skip).bounds()
        if bounds is None:
            raise ValueError("no triangles")
        rotation = yaw_rotation(model.yaw)
        native = np.abs(UP_ROTATIONS["y"] @ rotation) @ (bounds[1] - bounds[0]) * model.unit   # z-up metres
        size = native * (model.longest_m / max(float(native.max()), 1e-9))
        return AssetRecord(
            id=f"{self.name}/{rid}", name=model.name, category=model.category, source=self.name,
            licence=model_licence(path), kind="mesh", path=str(path), tags=model.tags, up_axis="y",
            unit_scale=model.unit, size_m=tuple(round(max(float(s), 1e-3), 6) for s in size),
            model_rotation=tuple(float(x) for x in rotation.ravel()), creator="FlightGear contributors",
            extra={"skip": list(skip), "file": model.file, "native_longest_m": round(float(native.max()), 4)})
