// Who asks, and what they may do with a thing someone owns: the one set of ownership rules
// every route applies (docs/api.md, Identities and ownership).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "util/user_name.h"

namespace brdfa::server {

enum class Role { Student, Teacher };
const char* roleName(Role role);  // "student", "teacher"
// The role of that name; nullopt for any other text.
std::optional<Role> roleFromName(std::string_view name);

// The person a request acts for. In `none` mode every request is the nameless teacher, and
// every thing is owned by "" (nobody): the single-user service as it was before identities.
struct Identity {
  std::string user;         // "" in none mode
  std::string displayName;  // free text, shown as text
  Role role = Role::Teacher;
  std::string tokenId;  // tokens mode: the id of the token that authenticated the request

  bool teacher() const { return role == Role::Teacher; }
  // The owner recorded on a session, job or preset this person makes.
  const std::string& owner() const { return user; }
  // The owner recorded on a BRDF or upload this person makes: a teacher's saves are the
  // course's (owner ""), readable by everyone; a student's are their own.
  std::string libraryOwner() const { return teacher() ? std::string() : user; }
  // The prefix of this person's BRDF names: "alice/" for a student, "" for the course.
  std::string brdfNamespace() const { return teacher() ? std::string() : user + "/"; }
};

// The identity of `none` mode.
Identity localIdentity();

// May `who` read a thing owned by `owner`? `everyone` marks things the class may read
// (built-ins, the course library, a shared BRDF, the `default` session).
inline bool canRead(const Identity& who, std::string_view owner, bool everyone = false) {
  return everyone || who.teacher() || owner == who.user;
}
// May `who` change it? Its owner; a teacher also what nobody owns (the course, `default`).
inline bool canWrite(const Identity& who, std::string_view owner) {
  return owner == who.user || (who.teacher() && owner.empty());
}
// May `who` delete it? Who may change it, and a teacher anything (to free a student's quota or
// take down what should not be there).
inline bool canDelete(const Identity& who, std::string_view owner) { return canWrite(who, owner) || who.teacher(); }

// Names no joining student may get: the teacher's and words the UI shows for nobody.
bool isReservedUserName(std::string_view name);
// A display name as stored: control characters and invalid UTF-8 dropped, spaces trimmed, at
// most 64 bytes (cut at a character boundary); "" when nothing is left.
std::string cleanDisplayName(std::string_view raw);
// A user name made from a display name: lower-cased, runs of other characters as one '-',
// at most 32 characters; "student" when nothing is left.
std::string userNameFromDisplayName(std::string_view displayName);

}  // namespace brdfa::server
