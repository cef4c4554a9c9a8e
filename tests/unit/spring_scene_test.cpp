// Scene fields of the spring construction: material.mapping (Van Gelder 1998 or Lloyd, Szekely & Harders 2007) and
// springs.{structural, flexion, bending, bending_min_angle}, with their errors.
#include <catch2/catch.hpp>
#include <string>
#include <vector>

#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

struct Parsed {
  std::optional<Scene> scene;
  std::vector<std::string> errors;  // "LINE:COL: message"
  std::vector<std::string> notes;
};

Parsed parse(const std::string& text) {
  DiagnosticList diagnostics;
  Parsed parsed;
  parsed.scene = parse_scene("/scenes/s.yaml", text, diagnostics);
  for (const Diagnostic& d : diagnostics.items()) {
    parsed.errors.push_back(std::to_string(d.range.line) + ":" + std::to_string(d.range.column) + ": " + d.message);
    for (const auto& note : d.notes) parsed.notes.push_back(note);
  }
  return parsed;
}

const std::string kBox = "mesh: {box: {size: [0.02, 0.02, 0.01], cells: [2, 2, 1]}}\n";

}  // namespace

TEST_CASE("material.mapping selects the Young's modulus mapping", "[springs][scene]") {
  const Parsed plain = parse(kBox + "material: {youngs_modulus: 10}\n");
  REQUIRE(plain.scene);
  CHECK(plain.scene->material.mapping == StiffnessMapping::VanGelder1998);

  const Parsed lloyd = parse(kBox + "material: {youngs_modulus: 10, mapping: lloyd_szekely_harders_2007}\n");
  REQUIRE(lloyd.scene);
  CHECK(lloyd.scene->material.mapping == StiffnessMapping::LloydSzekelyHarders2007);
  const Parsed gelder = parse(kBox + "material: {youngs_modulus: 10, mapping: van_gelder_1998}\n");
  REQUIRE(gelder.scene);
  CHECK(gelder.scene->material.mapping == StiffnessMapping::VanGelder1998);
  CHECK(std::string(scene_name(StiffnessMapping::LloydSzekelyHarders2007)) == "lloyd_szekely_harders_2007");

  const Parsed typo = parse(kBox + "material: {youngs_modulus: 10, mapping: lloyd_szekely_harders_2070}\n");
  CHECK_FALSE(typo.scene);
  CHECK(typo.errors == std::vector<std::string>{
                           "2:41: material.mapping: 'lloyd_szekely_harders_2070' is not a Young's modulus mapping; use "
                           "van_gelder_1998 or lloyd_szekely_harders_2007"});
  CHECK(typo.notes == std::vector<std::string>{"did you mean 'lloyd_szekely_harders_2007'?"});

  const Parsed wrong_source = parse(kBox + "material: {stiffness: 10, mapping: van_gelder_1998}\n");
  CHECK_FALSE(wrong_source.scene);
  CHECK(wrong_source.errors ==
        std::vector<std::string>{"2:36: material.mapping: only allowed with 'youngs_modulus', 'rules' or 'table' (it "
                                 "maps Young's modulus to spring constants)"});
}

TEST_CASE("a scene with the Lloyd mapping builds k = 24/25 of Van Gelder's on tetrahedra", "[springs][scene]") {
  DiagnosticList diagnostics;
  const Parsed gelder = parse(kBox + "material: {youngs_modulus: 10}\n");
  const Parsed lloyd = parse(kBox + "material: {youngs_modulus: 10, mapping: lloyd_szekely_harders_2007}\n");
  REQUIRE(gelder.scene);
  REQUIRE(lloyd.scene);
  const auto built_gelder = build_scene(*gelder.scene, diagnostics);
  const auto built_lloyd = build_scene(*lloyd.scene, diagnostics);
  REQUIRE(built_gelder);
  REQUIRE(built_lloyd);
  CHECK(built_gelder->stiffness_description == "Van Gelder 1998 with E = 10 kPa");
  CHECK(built_lloyd->stiffness_description == "Lloyd, Szekely & Harders 2007 with E = 10 kPa");
  const auto& k_gelder = built_gelder->setup.springs.stiffness;
  const auto& k_lloyd = built_lloyd->setup.springs.stiffness;
  REQUIRE(k_gelder.size() == k_lloyd.size());
  for (std::size_t s = 0; s < k_gelder.size(); ++s)
    CHECK(k_lloyd[s] == Approx(24.0 / 25.0 * k_gelder[s]).epsilon(1e-12));

  // Through the rules: the liver rules for constant inputs, the same factor spring by spring.
  const std::string rules = std::string("material: {rules: ") + FMPC_SOURCE_DIR +
                            "/rulesets/liver_fibrosis/mamdani.fis, inputs: {HCV: 9.7, HBV: 9.5, ALD: 12, CLD: 11, "
                            "NAFLD: 11.2}";
  const Parsed fuzzy_gelder = parse(kBox + rules + "}\n");
  const Parsed fuzzy_lloyd = parse(kBox + rules + ", mapping: lloyd_szekely_harders_2007}\n");
  REQUIRE(fuzzy_gelder.scene);
  REQUIRE(fuzzy_lloyd.scene);
  const auto built_fuzzy_gelder = build_scene(*fuzzy_gelder.scene, diagnostics);
  const auto built_fuzzy_lloyd = build_scene(*fuzzy_lloyd.scene, diagnostics);
  REQUIRE(built_fuzzy_gelder);
  REQUIRE(built_fuzzy_lloyd);
  CHECK_THAT(built_fuzzy_lloyd->stiffness_description, Catch::StartsWith("Lloyd, Szekely & Harders 2007 with E from"));
  const auto& f_gelder = built_fuzzy_gelder->setup.springs.stiffness;
  const auto& f_lloyd = built_fuzzy_lloyd->setup.springs.stiffness;
  for (std::size_t s = 0; s < f_gelder.size(); ++s)
    CHECK(f_lloyd[s] == Approx(24.0 / 25.0 * f_gelder[s]).epsilon(1e-12));
  // The rules give 20.83 kPa (patient 3 of the demo): k = E x factor.
  CHECK(f_gelder[0] / k_gelder[0] == Approx(2.082838).epsilon(1e-5));
}

TEST_CASE("springs: bending springs and the shear key", "[springs][scene]") {
  const Parsed bending =
      parse(kBox + "material: {youngs_modulus: 10}\nsprings: {bending: true, bending_min_angle: 170}\n");
  REQUIRE(bending.scene);
  CHECK(bending.scene->triangle_springs.bending);
  CHECK(bending.scene->triangle_springs.bending_min_angle_degrees == 170.0);
  CHECK(bending.scene->triangle_springs.flexion);

  const Parsed angle = parse(kBox + "material: {youngs_modulus: 10}\nsprings: {bending_min_angle: 45}\n");
  CHECK_FALSE(angle.scene);
  CHECK(angle.errors == std::vector<std::string>{
                            "3:30: springs.bending_min_angle: expected an angle from 90 to 180 (degrees), got 45"});

  const Parsed shear = parse(kBox + "material: {youngs_modulus: 10}\nsprings: {shear: true}\n");
  CHECK_FALSE(shear.scene);
  CHECK(shear.errors ==
        std::vector<std::string>{"3:18: springs.shear: the thesis gives no rule for shear springs on a triangle mesh; "
                                 "its flexion springs (Fig. 3.4) join the two vertices across each shared edge, the "
                                 "diagonal that cloth models call a shear spring: use 'flexion' (and 'bending' for "
                                 "springs that skip a vertex)"});

  const Parsed unknown = parse(kBox + "material: {youngs_modulus: 10}\nsprings: {bendin: true}\n");
  CHECK_FALSE(unknown.scene);
  CHECK(unknown.errors == std::vector<std::string>{"3:11: springs.bendin: unknown key in springs; allowed: "
                                                   "'structural', 'flexion', 'bending', 'bending_min_angle' or "
                                                   "'volume_term'"});
  CHECK(unknown.notes == std::vector<std::string>{"did you mean 'bending'?"});
}
