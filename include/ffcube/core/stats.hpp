// Statistics as data: a set of counters and timers, each declared once with its report key and
// its merge rule, then merged (threads), flattened (worker sockets, MPI ranks) and written to a
// report by name, all generically. (pbrt-v4's STAT_COUNTER is the model; here a set belongs to
// the object that counts it, a provider's or a corrector's, not to the process.)
//
// A set is a plain struct whose members one list macro declares, one X(...) line each (every
// line of the macro but the last ending in a backslash, the comments in slash-star form):
//
//     #define FFCUBE_MY_STATS(X)
//         X(std::uint64_t, rows, sum, "my.rows")        /* rows seen */
//         X(double, worst, max, "my.worst_change")      /* largest |change| */
//         X(double, seconds, sum, "time.my")            /* CPU-seconds */
//         X(double, least_sum, min, "")                 /* not reported as is */
//     struct MyStats {
//         FFCUBE_STATS(MyStats, FFCUBE_MY_STATS)
//     };
//
// X(type, member, rule, key): type is std::uint64_t, double, or stats::PerPart<...> (a few values
// reported as key.part, such as a hemicube's five faces; give it a one-word alias first, since a
// macro argument cannot hold a comma); rule is sum, max or min; key is the report key ("": the
// report derives its own figure from the value, or does not show it). Counting is plain member
// access (`++st.rows`, `ScopedTimer t(st.seconds)`), so adding a counter takes that X line and the
// line that counts it: merge, the flat form and the report follow from the list.
#pragma once

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>

#include "ffcube/core/error.hpp"

namespace ffcube::stats {

// How two values of one statistic combine: added, or the larger or the smaller kept.
enum class Merge : std::uint8_t { sum, max, min };

// N values of one statistic, reported as "key.name" for each of Names.
template <class T, std::size_t N, const std::array<std::string_view, N>& Names>
struct PerPart : std::array<T, N> {
    static constexpr const std::array<std::string_view, N>& names = Names;
};

// What the list says of one member besides its type.
struct Info {
    std::string_view member;  // the member's name
    std::string_view key;     // its report key, "" for none
    Merge merge;
};

namespace detail {

template <class T>
struct is_parts : std::false_type {};
template <class T, std::size_t N, const std::array<std::string_view, N>& Names>
struct is_parts<PerPart<T, N, Names>> : std::true_type {};

template <class T>
constexpr T scalar_initial(Merge m) {
    static_assert(std::is_same_v<T, std::uint64_t> || std::is_same_v<T, double>,
                  "a statistic is a std::uint64_t or a double (or a PerPart of them)");
    // A minimum starts at +inf (UINT64_MAX): the smallest of nothing. A sum starts at 0, and so
    // does a maximum: maxima here are of magnitudes (|change|, counts), 0 when nothing was seen.
    if (m == Merge::min) {
        if constexpr (std::numeric_limits<T>::has_infinity) return std::numeric_limits<T>::infinity();
        else return std::numeric_limits<T>::max();
    }
    return T{};
}

template <class T>
constexpr void scalar_merge(Merge m, T& a, const T& b) {
    switch (m) {
        case Merge::sum: a += b; break;
        case Merge::max: a = b > a ? b : a; break;
        case Merge::min: a = b < a ? b : a; break;
    }
}

// The u64 words of one value: a count as itself, a double as its bits (exact both ways).
template <class T>
constexpr std::uint64_t to_word(T v) {
    if constexpr (std::is_same_v<T, double>) return std::bit_cast<std::uint64_t>(v);
    else return v;
}
template <class T>
constexpr T from_word(std::uint64_t w) {
    if constexpr (std::is_same_v<T, double>) return std::bit_cast<double>(w);
    else return w;
}

// Calls f on a scalar, or on each of a PerPart's values.
template <class T, class F>
constexpr void each_value(T& v, F&& f) {
    if constexpr (is_parts<std::remove_const_t<T>>::value) {
        for (auto& x : v) f(x);
    } else {
        f(v);
    }
}

}  // namespace detail

// The starting value of a member under its rule (the identity of the merge).
template <class T>
constexpr T initial(Merge m) {
    if constexpr (detail::is_parts<T>::value) {
        T t{};
        for (auto& x : t) x = detail::scalar_initial<typename T::value_type>(m);
        return t;
    } else {
        return detail::scalar_initial<T>(m);
    }
}

// into ⊕= from, member by member under each one's rule. Sums of integers are exact in any order;
// sums of doubles (timings, weights) are as exact as the order the caller merges in.
template <class S>
constexpr void merge(S& into, const S& from) {
    S::each_field([&](const Info& info, auto member) {
        auto& a = into.*member;
        const auto& b = from.*member;
        if constexpr (detail::is_parts<std::remove_cvref_t<decltype(a)>>::value) {
            for (std::size_t k = 0; k < a.size(); ++k) detail::scalar_merge(info.merge, a[k], b[k]);
        } else {
            detail::scalar_merge(info.merge, a, b);
        }
    });
}

// The number of u64 words of the flat form: one a scalar, one a part.
template <class S>
constexpr std::size_t words() {
    std::size_t n = 0;
    S s{};
    S::each_field([&](const Info&, auto member) { detail::each_value(s.*member, [&](auto&) { ++n; }); });
    return n;
}

// The flat form of a set: its values in declaration order, as u64 words (a double as its bits).
// It goes over the worker sockets and between MPI ranks; the same binary reads it back.
template <class S>
constexpr std::array<std::uint64_t, words<S>()> to_words(const S& s) {
    std::array<std::uint64_t, words<S>()> w{};
    std::size_t k = 0;
    S::each_field([&](const Info&, auto member) {
        detail::each_value(s.*member, [&](const auto& v) { w[k++] = detail::to_word(v); });
    });
    return w;
}

// The set back from its flat form (exactly words<S>() words).
template <class S>
S from_words(std::span<const std::uint64_t> w) {
    FFCUBE_CHECK_MSG(w.size() == words<S>(), "stats::from_words: a flat form of another length");
    S s{};
    std::size_t k = 0;
    S::each_field([&](const Info&, auto member) {
        detail::each_value(s.*member, [&](auto& v) { v = detail::from_word<std::remove_cvref_t<decltype(v)>>(w[k++]); });
    });
    return s;
}

// The merge rule of each word of the flat form (for a reduction that merges flat forms).
template <class S>
constexpr std::array<Merge, words<S>()> word_rules() {
    std::array<Merge, words<S>()> r{};
    std::size_t k = 0;
    S s{};
    S::each_field([&](const Info& info, auto member) { detail::each_value(s.*member, [&](auto&) { r[k++] = info.merge; }); });
    return r;
}

// Writes every member that has a key to r (anything with set(key, value): io/report.hpp's
// Report), in declaration order: a scalar at its key, a part at key.name.
template <class R, class S>
void report(R& r, const S& s) {
    S::each_field([&](const Info& info, auto member) {
        if (info.key.empty()) return;
        const auto& v = s.*member;
        if constexpr (detail::is_parts<std::remove_cvref_t<decltype(v)>>::value) {
            for (std::size_t k = 0; k < v.size(); ++k)
                r.set(std::string(info.key) + "." + std::string(v.names[k]), v[k]);
        } else {
            r.set(info.key, v);
        }
    });
}

}  // namespace ffcube::stats

// The members of a statistics set and its each_field(f), which calls f(Info, &Self::member) for
// each in declaration order (see the top of this file).
#define FFCUBE_STAT_MEMBER_(type, name, rule, key) type name = ::ffcube::stats::initial<type>(::ffcube::stats::Merge::rule);
#define FFCUBE_STAT_VISIT_(type, name, rule, key) \
    f(::ffcube::stats::Info{#name, key, ::ffcube::stats::Merge::rule}, &stats_self_::name);
#define FFCUBE_STATS(Self, LIST)                       \
    LIST(FFCUBE_STAT_MEMBER_)                          \
    using stats_self_ = Self;                          \
    template <class F>                                 \
    static constexpr void each_field(F&& f) {          \
        LIST(FFCUBE_STAT_VISIT_)                       \
    }
