// Building models: ports, children and checked couplings; routing through hierarchies.
#include <gtest/gtest.h>

#include <string>

#include "sim/coordinator.hpp"
#include "test_models.hpp"

using namespace rilbed::sim;
using namespace rilbed::sim::testing;

namespace {

/// Passive model with a string input, to provoke type mismatches.
class TextSink : public AtomicModel<std::vector<std::string>> {
 public:
  explicit TextSink(std::string id) : AtomicModel(std::move(id), {}), in(add_input<std::string>("in")) {}
  Port<std::string>& in;
  rilbed::TimeUs time_advance() const override { return kInfinity; }
  void output() override {}
  void internal_transition() override {}
  void external_transition(rilbed::TimeUs) override {
    for (const auto& text : in.messages()) state_.push_back(text);
  }
};

std::string what_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "(no std::invalid_argument)";
}

}  // namespace

TEST(Coupling, TypeMismatchNamesBothPorts) {
  Coupled top("top");
  auto& gen = top.emplace<Generator>("gen", 100, 1);
  auto& text = top.emplace<TextSink>("text");
  const std::string message = what_of([&] { top.couple(gen.out, text.in); });
  EXPECT_NE(message.find("'top/gen.out' (int)"), std::string::npos) << message;
  EXPECT_NE(message.find("'top/text.in'"), std::string::npos) << message;
  EXPECT_NE(message.find("string"), std::string::npos) << message;
  EXPECT_NE(message.find("types differ"), std::string::npos) << message;
  EXPECT_TRUE(top.couplings().empty());
}

TEST(Coupling, RejectsPortsOutsideTheModelAndItsChildren) {
  Coupled top("top");
  auto& mid = top.emplace<Coupled>("mid");
  auto& deep_sink = mid.emplace<Sink>("deep");
  auto& gen = top.emplace<Generator>("gen", 100, 1);
  // A grandchild's port must be reached through mid's own ports.
  EXPECT_NE(what_of([&] { top.couple(gen.out, deep_sink.in); }).find("direct children"), std::string::npos);
  Sink stranger("stranger");
  EXPECT_NE(what_of([&] { top.couple(gen.out, stranger.in); }).find("direct children"), std::string::npos);
}

TEST(Coupling, RejectsDirectionsThatFitNoKind) {
  Coupled top("top");
  auto& top_in = top.add_input<int>("in");
  auto& top_out = top.add_output<int>("out");
  auto& a = top.emplace<Processor>("a", 10);
  auto& b = top.emplace<Processor>("b", 10);
  EXPECT_THROW(top.couple(a.out, b.out), std::invalid_argument);     // out -> out of siblings
  EXPECT_THROW(top.couple(a.in, b.in), std::invalid_argument);       // in -> in of siblings
  EXPECT_THROW(top.couple(top_in, top_out), std::invalid_argument);  // own in -> own out
  EXPECT_THROW(top.couple(top_out, a.in), std::invalid_argument);    // own out -> child
  EXPECT_THROW(top.couple(a.in, top_out), std::invalid_argument);    // child in -> own out
  EXPECT_NO_THROW(top.couple(top_in, a.in));                         // EIC
  EXPECT_NO_THROW(top.couple(a.out, b.in));                          // IC
  EXPECT_NO_THROW(top.couple(b.out, top_out));                       // EOC
  EXPECT_NE(what_of([&] { top.couple(a.out, b.in); }).find("exists already"), std::string::npos);
  EXPECT_EQ(top.couplings().size(), 3u);
}

TEST(Coupling, ChecksNamesAndParents) {
  Coupled top("top");
  auto gen = std::make_shared<Generator>("gen", 100, 1);
  top.add(gen);
  EXPECT_EQ(gen->parent(), &top);
  EXPECT_EQ(gen->path(), "top/gen");
  EXPECT_THROW(top.add(std::make_shared<Sink>("gen")), std::invalid_argument);  // sibling id taken
  Coupled other("other");
  EXPECT_THROW(other.add(gen), std::invalid_argument);  // already has a parent
  EXPECT_THROW(top.add(std::shared_ptr<Sink>()), std::invalid_argument);
  EXPECT_THROW(Sink(""), std::invalid_argument);
  EXPECT_THROW(gen->add_output<double>("out"), std::invalid_argument);  // port name taken
  EXPECT_NO_THROW(gen->add_input<double>("out"));                       // inputs and outputs are separate
  EXPECT_EQ(&gen->output_port<int>("out"), &gen->out);
  EXPECT_THROW(gen->output_port<double>("out"), std::invalid_argument);
  EXPECT_THROW(gen->input_port<int>("missing"), std::invalid_argument);
  EXPECT_EQ(gen->find_output("missing"), nullptr);
}

TEST(Coupling, ChildOutlivingItsParentIsDetached) {
  auto gen = std::make_shared<Generator>("gen", 100, 1);
  {
    Coupled top("top");
    top.add(gen);
  }
  EXPECT_EQ(gen->parent(), nullptr);
  EXPECT_EQ(gen->path(), "gen");
}

// top: gen -IC-> mid.in -EIC-> inner.in -EIC-> proc.in; proc.out -EOC-> inner.out
// -EOC-> mid.out -IC-> sink.in and mid.out -EOC-> top.out.
TEST(Coupling, RoutesThroughNestedCoupledModels) {
  auto top = std::make_shared<Coupled>("top");
  auto& top_out = top->add_output<int>("out");
  auto& gen = top->emplace<Generator>("gen", 100, 2);
  auto& mid = top->emplace<Coupled>("mid");
  auto& sink = top->emplace<Sink>("sink");
  auto& mid_in = mid.add_input<int>("in");
  auto& mid_out = mid.add_output<int>("out");
  auto& inner = mid.emplace<Coupled>("inner");
  auto& inner_in = inner.add_input<int>("in");
  auto& inner_out = inner.add_output<int>("out");
  auto& proc = inner.emplace<Processor>("proc", 30);
  top->couple(gen.out, mid_in);
  mid.couple(mid_in, inner_in);
  inner.couple(inner_in, proc.in);
  inner.couple(proc.out, inner_out);
  mid.couple(inner_out, mid_out);
  top->couple(mid_out, sink.in);
  top->couple(mid_out, top_out);

  FastClock clock;
  Coordinator coordinator(top, clock);
  ASSERT_EQ(coordinator.atomics().size(), 3u);  // gen, proc, sink: depth-first order
  EXPECT_EQ(coordinator.atomics()[0], &gen);
  EXPECT_EQ(coordinator.atomics()[1], &proc);
  EXPECT_EQ(coordinator.atomics()[2], &sink);
  std::vector<std::pair<rilbed::TimeUs, std::vector<int>>> at_top;
  coordinator.on_output<int>(
      top_out, [&](rilbed::TimeUs t_us, const std::vector<int>& messages) { at_top.emplace_back(t_us, messages); });
  coordinator.run_until(1000);
  EXPECT_EQ(sink.state().received, (std::vector<std::pair<rilbed::TimeUs, int>>{{130, 1}, {230, 2}}));
  EXPECT_EQ(at_top, (std::vector<std::pair<rilbed::TimeUs, std::vector<int>>>{{130, {1}}, {230, {2}}}));
  EXPECT_TRUE(top_out.empty());  // bags are cleared after each step
}

TEST(Coupling, TwoChainsToOnePortDeliverOnce) {
  auto top = std::make_shared<Coupled>("top");
  auto& gen = top->emplace<Generator>("gen", 100, 1);
  auto& mid = top->emplace<Coupled>("mid");
  auto& a = mid.add_input<int>("a");
  auto& b = mid.add_input<int>("b");
  auto& sink = mid.emplace<Sink>("sink");
  top->couple(gen.out, a);
  top->couple(gen.out, b);
  mid.couple(a, sink.in);
  mid.couple(b, sink.in);
  FastClock clock;
  Coordinator coordinator(top, clock);
  coordinator.run_until(1000);
  EXPECT_EQ(sink.state().received, (std::vector<std::pair<rilbed::TimeUs, int>>{{100, 1}}));
}

TEST(Coupling, FanOutCopiesToEveryDestination) {
  auto top = std::make_shared<Coupled>("top");
  auto& gen = top->emplace<Generator>("gen", 100, 2);
  auto& first = top->emplace<Sink>("first");
  auto& second = top->emplace<Sink>("second");
  top->couple(gen.out, first.in);
  top->couple(gen.out, second.in);
  FastClock clock;
  Coordinator coordinator(top, clock);
  coordinator.run_until(1000);
  const std::vector<std::pair<rilbed::TimeUs, int>> expected{{100, 1}, {200, 2}};
  EXPECT_EQ(first.state().received, expected);
  EXPECT_EQ(second.state().received, expected);
}
