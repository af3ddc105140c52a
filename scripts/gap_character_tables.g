# Character tables from GAP, an independent source for the symmetry crate's tests.
# Regenerate (Debian: apt-get install gap-core gap-libs gap-character-tables):
#   gap -q scripts/gap_character_tables.g > symmetry/tests/data/gap_character_tables.json
# Each character value is a cyclotomic, printed as its coefficients c_k in the basis
# E(n)^k, k = 0..n-1 (GAP's COEFFS_CYC); its value is sum_k c_k exp(2 pi i k / n).
LoadPackage("ctbllib");
tables := [
  ["C7v", "CharacterTable(DihedralGroup(14))", CharacterTable(DihedralGroup(14))],
  ["C8v", "CharacterTable(DihedralGroup(16))", CharacterTable(DihedralGroup(16))],
  ["C12v", "CharacterTable(DihedralGroup(24))", CharacterTable(DihedralGroup(24))],
  ["C2v", "CharacterTable(DihedralGroup(4))", CharacterTable(DihedralGroup(4))],
  ["I", "CharacterTable(\"A5\")", CharacterTable("A5")],
  ["Ih", "CharacterTable(\"2xA5\")", CharacterTable("2xA5")]
];
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
for k in [1..Length(tables)] do
  e := tables[k];
  t := e[3];
  Print("  \"", e[1], "\": {\n");
  Print("    \"gap\": \"", ReplacedString(e[2], "\"", "\\\""), "\",\n");
  Print("    \"class_sizes\": "); PrintList(SizesConjugacyClasses(t), Print); Print(",\n");
  Print("    \"element_orders\": "); PrintList(OrdersClassRepresentatives(t), Print); Print(",\n");
  Print("    \"irreps\": ");
  PrintList(Irr(t), function(chi)
    PrintList(ValuesOfClassFunction(chi), function(v) PrintList(COEFFS_CYC(v), Print); end);
  end);
  Print("\n  }");
  if k < Length(tables) then Print(","); fi;
  Print("\n");
od;
Print("}\n");
QUIT;
