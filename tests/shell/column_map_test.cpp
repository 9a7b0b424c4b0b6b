// Column maps (`--columns`, "columns" in a configuration): names, indices, scales, matrix
// slices, and errors that name the entry.

#include "shell/column_map.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace millwatch::shell {
namespace {

std::string error_of(const std::string& text) {
  try {
    parse_column_map(text);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(ColumnMap, NamesIndicesAndScales) {
  const ColumnMap m = parse_column_map("t=Time*0.001, fx=2,fy=Fy*-1,fz=force z*1e3");
  EXPECT_EQ(m.t().source, "Time");
  EXPECT_DOUBLE_EQ(m.t().scale, 0.001);
  EXPECT_EQ(m.force(0).index, 2);
  EXPECT_TRUE(m.force(0).source.empty());
  EXPECT_EQ(m.force(1).source, "Fy");
  EXPECT_DOUBLE_EQ(m.force(1).scale, -1.0);
  EXPECT_EQ(m.force(2).source, "force z");
  EXPECT_DOUBLE_EQ(m.force(2).scale, 1000.0);
  EXPECT_FALSE(m.fs().given());
  EXPECT_EQ(m.to_string(), "t=Time*0.001,fx=2,fy=Fy*-1,fz=force z*1000");
  EXPECT_EQ(parse_column_map(m.to_string()).to_string(), m.to_string());
}

TEST(ColumnMap, ANameWithAStarWritesItsScale) {
  // Found by fuzz_text_recording: "fy=a*1" is the name "a" scaled by 1, written back as "fy=a".
  const ColumnMap m = parse_column_map("fx=1,fy=F*x*1,fz=2");
  EXPECT_EQ(m.force(1).source, "F*x");
  EXPECT_EQ(m.to_string(), "fx=1,fy=F*x*1,fz=2");
  EXPECT_EQ(parse_column_map(m.to_string()).force(1).source, "F*x");
}

TEST(ColumnMap, AnExplicitScaleOfOneReadsBackTheSame) {
  // "*1" says the map's scale is the whole conversion (a units row's factor does not apply):
  // written back as "fx=Fx", it would have read back unscaled, the units row applying again.
  const ColumnMap m = parse_column_map("t=time_ms*0.001,fx=Fx*1,fy=Fy,fz=Fz");
  EXPECT_TRUE(m.force(0).scaled);
  EXPECT_FALSE(m.force(1).scaled);
  EXPECT_EQ(m.to_string(), "t=time_ms*0.001,fx=Fx*1,fy=Fy,fz=Fz");
  EXPECT_TRUE(parse_column_map(m.to_string()).force(0).scaled);
}

TEST(ColumnMap, MatrixSlicesKeepTheirComma) {
  const ColumnMap m = parse_column_map("fx=F(:,1),fy=F(:,2),fz=F(3,:),fs=rate");
  EXPECT_EQ(m.force(0).source, "F(:,1)");
  EXPECT_EQ(m.force(2).source, "F(3,:)");
  EXPECT_EQ(m.fs().source, "rate");
}

TEST(ColumnMap, ErrorsNameTheEntry) {
  EXPECT_EQ(error_of("fx=1,fy=2"),
            "columns: fz is missing (fx, fy and fz are all needed; t and fs are optional)");
  EXPECT_EQ(error_of("fq=1,fx=1,fy=2,fz=3"),
            "columns: unknown key \"fq\" (allowed: t, fx, fy, fz, fs)");
  EXPECT_EQ(error_of("fx=1,fy=2,fz=3*abc"),
            "columns: fz: scale \"abc\" is not a finite non-zero number");
  EXPECT_EQ(error_of("fx=1,fy=2,fz=0"), "columns: fz: column index 0 is out of range [1, 100000]");
  EXPECT_EQ(error_of("fx=1,fx=2,fy=2,fz=3"), "columns: fx is given twice");
  EXPECT_EQ(error_of("fx"), "columns: \"fx\" is not key=column (e.g. t=Time,fx=Fx,fy=Fy,fz=Fz)");
  EXPECT_EQ(error_of(""), "columns: no columns named (e.g. t=Time,fx=Fx,fy=Fy,fz=Fz)");
  EXPECT_EQ(error_of("fx=1,fy=2,fz=*2"), "columns: fz: no column named");
  // One column read as two quantities: a cut that was not recorded (Fy a copy of Fx).
  EXPECT_EQ(error_of("fx=1,fy=1,fz=3"),
            "columns: fx and fy both read 1 (each needs its own column)");
  EXPECT_EQ(error_of("t=Time,fx=Fx,fy=Fy,fz=Time"),
            "columns: t and fz both read Time (each needs its own column)");
  EXPECT_EQ(error_of("fx=1,fy=1*2,fz=3"),
            "columns: fx and fy both read 1 (each needs its own column)");
}

TEST(ColumnMap, JsonTextOrObject) {
  const ColumnMap a = column_map_from_json("t=Time,fx=Fx,fy=Fy,fz=Fz");
  EXPECT_EQ(a.to_string(), "t=Time,fx=Fx,fy=Fy,fz=Fz");
  const ColumnMap b = column_map_from_json({{"fx", 1}, {"fy", "2*2"}, {"fz", "Fz"}});
  EXPECT_EQ(b.to_string(), "fx=1,fy=2*2,fz=Fz");
  try {
    column_map_from_json({{"fx", 1.5}, {"fy", 2}, {"fz", 3}}, "monitor.columns");
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "monitor.columns.fx: expected a column name or index, got number");
  }
  try {
    column_map_from_json("fx=1", "columns");
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("columns: fy is missing"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace millwatch::shell
