"""The exception vkas raises for a broken valid-usage rule."""


class ValidationError(Exception):
    """A Vulkan valid-usage rule was broken.

    ``vuid`` is the rule's full name (``VUID-...``), as vkas reports it through the device's debug messenger;
    ``message`` is vkas's message for it (``Validation Error: [ VUID ] | vkCommand(): detail``); ``messages`` lists
    every ``(vuid, message)`` the failing call reported, the first one first.
    """

    def __init__(self, vuid, message, messages=None):
        super().__init__(f"{vuid}: {message}" if vuid else message)
        self.vuid = vuid
        self.message = message
        self.messages = list(messages) if messages else [(vuid, message)]

    __module__ = "vkas"

    def __reduce__(self):
        return (type(self), (self.vuid, self.message, self.messages))
