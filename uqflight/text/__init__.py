"""Text in and out: what the command line prints (`console`), how figures name outputs and parameters
(`labels`), strict JSON laid out for reading (`json_text`), and text files read within a bound
(`bounded`); the error of a value refused at a field (`FieldError`)."""


class FieldError(ValueError):
    """A value refused at a field of the campaign (`field`, a dotted path such as `design.level`), with what
    was expected (`message`); its text is "FIELD: MESSAGE". `campaign.schema.CampaignError` adds the file."""

    def __init__(self, field: str, message: str):
        self.field, self.message = field, message
        super().__init__(f"{field}: {message}" if field else message)
