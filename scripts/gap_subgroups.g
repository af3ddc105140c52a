# Conjugacy classes of subgroups from GAP, an independent source for the symmetry crate's
# lattice tests (symmetry/tests/lattice_gap.rs).
# Regenerate (Debian: apt-get install gap; GAP 4.12):
#   gap -q scripts/gap_subgroups.g > symmetry/tests/data/gap_subgroups.json
#
# Each group is built as a matrix group in the crate's own coordinates, so that geometric
# facts (rotations, mirrors, the inversion -I, the crate's first mirror y = 0) can be read off
# the representatives:
# - C_n: the rotation by 2 pi / n in the plane (2x2, cyclotomic entries);
# - C_nv: that rotation and the first mirror s = diag(1, -1) (the plane y = 0);
# - I: the half-turn diag(-1, -1, 1) and the rotation by 72 degrees about the vertex
#   (0, 1, phi) of the icosahedron with vertices at the cyclic permutations of (0, +-1, +-phi);
# - Ih: those and -I.
# The abstract group (DihedralGroup(2n), CyclicGroup(n), AlternatingGroup(5),
# SmallGroup(120, 35) = A5 x C2) is checked to be isomorphic (IdGroup), and its number of
# classes of subgroups is printed as well ("abstract_class_count").
#
# For every class of subgroups (GAP's ConjugacyClassesSubgroups order, 0-based in the JSON):
#   order, size (number of conjugates), cyclic, structure (StructureDescription),
#   rotations (elements of determinant 1), mirrors (reflections: det -1, trace d - 2),
#   inversion (contains -I; 3-D groups only), first_mirror (contains a conjugate of s; C_nv
#   only), subconjugate (the classes j having a conjugate contained in this representative,
#   itself included).
SetPrintFormattingStatus("*stdout*", false);
# Bound before the loop below refers to them (avoids "unbound global" warnings).
G := fail; d := 0; H := fail; ccs := []; reps := [];

Rot2 := function(n)
  local c, s;
  c := (E(n) + E(n)^-1) / 2;
  s := (E(n) - E(n)^-1) / (2 * E(4));
  return [[c, -s], [s, c]];
end;

phi := (1 + Sqrt(5)) / 2;
r5 := [[phi - 1, -phi, 1], [phi, 1, phi - 1], [-1, phi - 1, phi]] / 2;
h2 := [[-1, 0, 0], [0, -1, 0], [0, 0, 1]];
mirror := [[1, 0], [0, -1]];

# [name, description, matrix group, abstract group, first mirror or fail, 3-D?]
entries := [];
for n in [1, 2, 3, 4, 5, 6, 7, 8, 12] do
  Add(entries, [Concatenation("C", String(n), "v"),
    Concatenation("Group(Rot2(", String(n), "), diag(1,-1)) ~ DihedralGroup(", String(2 * n), ")"),
    Group(Rot2(n), mirror), DihedralGroup(2 * n), mirror, false]);
od;
for n in [6, 7, 12] do
  Add(entries, [Concatenation("C", String(n)),
    Concatenation("Group(Rot2(", String(n), ")) ~ CyclicGroup(", String(n), ")"),
    Group(Rot2(n)), CyclicGroup(n), fail, false]);
od;
Add(entries, ["I", "Group(r5, diag(-1,-1,1)) ~ AlternatingGroup(5)",
  Group(r5, h2), AlternatingGroup(5), fail, true]);
Add(entries, ["Ih", "Group(r5, diag(-1,-1,1), -I) ~ SmallGroup(120,35) = A5 x C2",
  Group(r5, h2, -IdentityMat(3)), SmallGroup(120, 35), fail, true]);

PrintList := function(l, f)
  local i;
  Print("[");
  for i in [1..Length(l)] do
    if i > 1 then Print(", "); fi;
    f(l[i]);
  od;
  Print("]");
end;

Print("{\n");
for k in [1..Length(entries)] do
  e := entries[k];
  G := e[3];
  d := Length(One(G));
  if IdGroup(G) <> IdGroup(e[4]) then
    Error(e[1], ": the matrix group is not isomorphic to the abstract group");
  fi;
  ccs := ConjugacyClassesSubgroups(G);
  reps := List(ccs, Representative);
  Print("  \"", e[1], "\": {\n");
  Print("    \"gap\": \"", e[2], "\",\n");
  Print("    \"id_group\": "); PrintList(IdGroup(G), Print); Print(",\n");
  Print("    \"abstract_class_count\": ", Length(ConjugacyClassesSubgroups(e[4])), ",\n");
  Print("    \"classes\": [\n");
  for i in [1..Length(ccs)] do
    H := reps[i];
    Print("      {\"order\": ", Size(H), ", \"size\": ", Size(ccs[i]),
      ", \"cyclic\": ", IsCyclic(H),
      ", \"structure\": \"", StructureDescription(H), "\"",
      ", \"rotations\": ", Number(AsList(H), m -> DeterminantMat(m) = 1),
      ", \"mirrors\": ", Number(AsList(H), m -> DeterminantMat(m) = -1 and TraceMat(m) = d - 2));
    if e[6] then
      Print(", \"inversion\": ", -One(G) in H);
    fi;
    if e[5] <> fail then
      Print(", \"first_mirror\": ", ForAny(AsList(ConjugacyClass(G, e[5])), m -> m in H));
    fi;
    Print(", \"subconjugate\": ");
    PrintList(Filtered([1..Length(ccs)],
      j -> Size(reps[j]) <= Size(H) and ForAny(AsList(ccs[j]), K -> IsSubset(H, K))) - 1, Print);
    Print("}");
    if i < Length(ccs) then Print(","); fi;
    Print("\n");
  od;
  Print("    ]\n  }");
  if k < Length(entries) then Print(","); fi;
  Print("\n");
od;
Print("}\n");
QUIT;
